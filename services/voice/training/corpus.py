"""What the spotter is trained and measured on: the vocabulary, the negatives and the voice splits.

Splits differ in how the speech is *made*, not only in seed:

- `train` (fit the head): espeak-ng accents and variants of `ESPEAK_TRAIN_*` and three recorded
  speakers (`RECORDED_TRAIN`): flite kal16 (diphone), flite awb (clustergen) and Festival ked
  (diphone); negatives from `NEIGHBOURS_TRAIN`, `PHRASES_TRAIN`, a sample of the pocketsphinx
  dictionary and (`two_edit_neighbours`) words two phonemes from a command that keep its vowel.
- `tune` (choose thresholds and the confidence calibration): the same engines, other espeak variants.
- `heldout` (the bench only): flite rms and slt (two speakers the head never heard), Festival's kal
  voice (another synthesiser), espeak-ng accents and variants not used above, and the non-command
  words of `services.voice.synth.OOV_HELDOUT`, which no other split contains. `HELDOUT_EXTRA`
  (Festival's HTS slt) is a further held-out family the bench reports on its own.

Homophones of a command (same pronunciation in the CMU dictionary, e.g. "know" for "no", "y" and
"wye" for "why") are never negatives: they are the command. Nor are the words espeak-ng itself says
exactly like a command (`tts_homophones`: "wei" and "wy" are `w'aI`, as "why"), in train and tune.

One-edit neighbours (`neighbour_split`): every dictionary word whose pronunciation is one phoneme
insertion, deletion or substitution away from a command's ("go" -> glow, goat, so, ago, ...), grouped
by pronunciation, are split at random with a fixed seed into train / tune / held-out groups *before*
any training, so the held-out confusable words are systematic and were never seen when fitting or
choosing thresholds.
"""

from __future__ import annotations

import random
import re
from functools import lru_cache
from pathlib import Path

from schemas.messages import Command
from services.voice.synth import OOV_HELDOUT, OOV_TUNE

VOCABULARY: tuple[str, ...] = tuple(c.value for c in Command)
"""The words the spotter is trained on, in class order; "other" is the last class."""

ESPEAK_TRAIN_ACCENTS = ("en-us", "en-gb", "en-gb-x-rp", "en-gb-x-gbclan", "en-gb-x-gbcwmd")
ESPEAK_HELDOUT_ACCENTS = ("en-029", "en-gb-scotland", "en-us-nyc")
ESPEAK_TRAIN_VARIANTS = (
    "", "m1", "m3", "m5", "m6", "m8", "f1", "f2", "f3", "klatt", "klatt2", "klatt4", "Andy", "Annie",
    "adam", "anika", "belinda", "benjamin", "david", "edward", "grandma", "grandpa", "john", "linda",
    "max", "michel", "norbert", "paul", "pablo", "Alicia", "Gene", "Lee", "Mike", "iven", "caleb",
)
ESPEAK_TUNE_VARIANTS = ("m2", "f5", "klatt3", "Alex", "Andrea", "antonio", "boris", "ed", "gustave", "Hugo")
ESPEAK_HELDOUT_VARIANTS = ("m4", "m7", "f4", "klatt5", "aunty", "Denis", "Jacky", "marcelo", "Michael", "Storm")
RECORDED_TRAIN = ("flite:kal16", "flite:awb", "festival:ked")
"""The training voices made from recordings of a speaker (not espeak-ng's formant synthesis)."""
FOREIGN_TRAIN = ("foreign:cs_dita", "foreign:cs_krb", "foreign:cs_machac", "foreign:cs_ph", "foreign:fi_lj",
                 "foreign:fi_mv")
"""Recorded speakers of other languages (Festival's Czech and Finnish voices: two women, a child, three men)
saying the English words from their CMU phonemes (`tts.foreign`): the `foreign` training split only (round 11),
never tune, recorded-tune or held-out. The Italian (lp, pc) and Catalan (ona) voices were screened out: the
committed head recognised fewer than 10 of 28 of their clean commands (docs/experiments/voice-rounds.md, round 11)."""
RECORDED_MORE = ("mbrola:us2", "mbrola:us3", "mbrola:en1", "rhvoice:alan", "rhvoice:bdl", "rhvoice:clb")
"""Six more recorded speakers, from two more engines (Debian contrib/non-free: MBROLA's diphones through espeak-ng,
three men; RHVoice's statistical-parametric voices, two men and a woman), added to `RECORDED_TRAIN` by
`dataset.with_more_recorded`: in the default head's training splits since round voice19c (`train.SHIPPED_MORE_VOICES`),
not in its tune splits. Never a held-out speaker: RHVoice's slt is flite's held-out slt,
so it is held out too (`HELDOUT_EXTRA`), with MBROLA's us1 and the whole SVOX Pico engine."""
RECORDED_GB = ("festival:rab", "festival:don")
"""Two more recorded speakers, both British men, through Festival's diphone voices (Debian contrib, with non-free's
festlex-oald: festvox-rablpc16k, festvox-don; don is a minimal 10 kHz voice): added after `RECORDED_MORE` by
`dataset.with_more_recorded(sizes, "train+gb")` (round voice29), in the training splits only. No split or bench row
used them before: the committed head heard 21 of don's 28 clean commands, none of its four "go"s (a British "go", as
Pico en-GB and MBROLA en1 say it)."""
HELDOUT_OTHER_ENGINES = ("flite:rms", "flite:slt", "festival:kal")
HELDOUT_NEURAL = ("piper:en_US-joe-medium", "kokoro:jm_kumo", "kokoro:jf_nezumi")
"""Neural voices, held out (stop 45): Piper's joe (VITS, trained on an American man's recordings) and two of Kokoro-82M's
five Japanese voices (a man's and a woman's) saying English phonemes. Kokoro's other three (`NEURAL_TRAIN`) were in no
split when these were chosen, so that a round training on neural voices can take them and leave these three held out."""
NEURAL_TRAIN = ("kokoro:jf_alpha", "kokoro:jf_gongitsune", "kokoro:jf_tebukuro")
"""Kokoro's three other voices (all women): the `neural` training split's (round voice22; fitted on only when
`Sizes.neural_positives` > 0, `train --neural N`), never tune or held-out."""
HELDOUT_EXTRA = ("festival:slt_hts", "pico:en-US", "pico:en-GB", "mbrola:us1", "rhvoice:slt", *HELDOUT_NEURAL)
"""Held-out voices the bench reports in their own rows, outside its "ALL" (comparable with earlier runs): Festival's
HTS slt (round v3), and since round voice19 SVOX Pico's two voices (an engine no split trains on), MBROLA's us1
(the one MBROLA voice no split trains on) and RHVoice's slt (the held-out slt speaker through another engine); since
stop 45 the neural voices of `HELDOUT_NEURAL`, the kind of voice the issue found the spotter barely heard."""

NEIGHBOURS_TRAIN: dict[str, tuple[str, ...]] = {
    "stand": ("sand", "stamp", "standing", "understand", "stem", "stab", "span", "tanned", "stained", "strand",
              "planned", "land", "stance", "stun", "than"),
    "down": ("town", "dawn", "done", "den", "dine", "round", "brown", "crown", "drown", "dune", "noun", "clown",
             "count", "pound", "about", "downtown"),
    "yes": ("yet", "yeah", "mess", "chess", "yell", "yam", "jest", "nest", "press", "dress", "test", "west",
            "youth", "year", "ye", "yesterday", "essay"),
    "no": ("now", "so", "toe", "nor", "gnaw", "knee", "nine", "own", "show", "near", "not", "nut",
           "nod", "oh", "noon", "known", "mow"),
    "go": ("goat", "ghost", "though", "grow", "gore", "got", "gut", "gum", "good", "coat", "dough", "bow",
           "going", "golf", "game", "gap", "guy", "gopher", "cold", "yo", "row", "home", "gone",
           "gaze", "o", "owe", "toast", "dog", "go-kart"),
    "stop": ("top", "shop", "stock", "stuck", "stomp", "spot", "slop", "drop", "crop", "strap", "swap",
             "stall", "stoop", "sloppy", "tops", "hop"),
    "why": ("white", "wide", "wine", "while", "wise", "way", "wait", "high", "buy", "bye", "try", "fly", "my",
            "sky", "wife", "wire", "whale", "eye", "we", "wow", "what", "hi"),
}
PHRASES_TRAIN = (
    "thanks a lot", "come here", "turn left", "turn right", "hello there", "how are you", "what is that",
    "nice to meet you", "look at me", "one two three", "red card", "the king of hearts", "let me see",
    "open the door", "good night", "all right", "that one", "I don't think so", "maybe later", "very good",
)


@lru_cache(maxsize=1)
def _cmudict() -> dict[str, list[str]]:
    import pocketsphinx

    path = Path(pocketsphinx.get_model_path()) / "en-us" / "cmudict-en-us.dict"
    prons: dict[str, list[str]] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        word, _, pron = line.partition(" ")
        prons.setdefault(word.split("(")[0], []).append(pron.strip())
    return prons


# The three word sets below each scan the whole dictionary (135,000 pronunciations, about half a second), and building
# one training split asks for them several times: each is made once per process and handed out as a fresh copy.
@lru_cache(maxsize=1)
def _homophones() -> dict[str, frozenset[str]]:
    prons = _cmudict()
    extra = {"why": {"y", "wye", "whye"}, "no": {"know", "noh", "knoe"}, "go": {"goh"}}
    out: dict[str, frozenset[str]] = {}
    for word in VOCABULARY:
        own = set(prons.get(word, []))
        out[word] = frozenset({w for w, ps in prons.items() if own.intersection(ps)} | extra.get(word, set()) | {word})
    return out


def homophones() -> dict[str, set[str]]:
    """Every dictionary word pronounced like a command (plus spellings of the command itself)."""
    return {word: set(words) for word, words in _homophones().items()}


@lru_cache(maxsize=1)
def _forbidden_negatives() -> frozenset[str]:
    bad = set().union(*_homophones().values())
    for word in VOCABULARY:  # plurals and other forms of the commands themselves are ambiguous
        bad |= {word + "s", word + "es", word + "ped", word + "ping", word + "'s"}
    return frozenset(bad)


def forbidden_negatives() -> set[str]:
    return set(_forbidden_negatives())


@lru_cache(maxsize=1)
def _plain_words() -> tuple[str, ...]:
    bad = _forbidden_negatives() | set(OOV_HELDOUT) | set(OOV_TUNE)
    return tuple(sorted(w for w in _cmudict() if w.isalpha() and w.isascii() and 2 <= len(w) <= 8 and w not in bad))


def common_words(n: int, seed: int) -> list[str]:
    """`n` plain dictionary words (2-8 letters), none a homophone of a command or a held-out word."""
    return random.Random(seed).sample(_plain_words(), n)


def negatives_train(n_common: int, seed: int) -> list[str]:
    bad = forbidden_negatives() | set(OOV_HELDOUT)
    words = [w for ws in NEIGHBOURS_TRAIN.values() for w in ws] + list(PHRASES_TRAIN)
    clean = [w for w in words if w not in bad]
    assert len(clean) == len(words), f"homophone or held-out word in the training negatives: {set(words) - set(clean)}"
    return clean + common_words(n_common, seed)


NEIGHBOUR_SEED = 7
NEIGHBOUR_FRACTIONS = (("train", 0.55), ("tune", 0.15), ("heldout", 0.30))


_NO_STRESS = str.maketrans("", "", "0123456789")


def _phones(pron: str) -> tuple[str, ...]:
    """A CMUdict pronunciation's phonemes, stress digits removed (called for every dictionary word: kept cheap)."""
    return tuple(pron.translate(_NO_STRESS).split())


def one_edit(a: tuple[str, ...], b: tuple[str, ...]) -> bool:
    """True if phoneme strings `a` and `b` differ by exactly one insertion, deletion or substitution."""
    if a == b or abs(len(a) - len(b)) > 1:
        return False
    if len(a) == len(b):
        return sum(x != y for x, y in zip(a, b, strict=True)) == 1
    short, long_ = (a, b) if len(a) < len(b) else (b, a)
    return any(long_[:i] + long_[i + 1 :] == short for i in range(len(long_)))


@lru_cache(maxsize=1)
def one_edit_neighbours() -> list[tuple[str, ...]]:
    """Groups of dictionary words one phoneme edit (stress ignored) from a command's pronunciation,
    words said alike in one group (a word with two pronunciations joins both groups into one);
    homophones and forms of the commands are left out. Each group's words are shortest first."""
    prons = _cmudict()
    commands = [_phones(p) for w in VOCABULARY for p in prons.get(w, [])]
    bad = forbidden_negatives()
    by_pron: dict[tuple[str, ...], set[str]] = {}
    for word, ps in prons.items():
        if not (word.isalpha() and word.isascii()) or word in bad:
            continue
        for pron in ps:
            ph = _phones(pron)
            if ph not in commands and any(one_edit(ph, c) for c in commands):
                by_pron.setdefault(ph, set()).add(word)
    groups: list[set[str]] = []
    for _, words in sorted(by_pron.items()):
        joined = [g for g in groups if g & words]
        for g in joined:
            groups.remove(g)
            words = words | g
        groups.append(set(words))
    return sorted((tuple(sorted(g, key=lambda w: (len(w), w))) for g in groups), key=lambda g: g[0])


@lru_cache(maxsize=4)
def neighbour_split(trained: frozenset[str] = frozenset()) -> dict[str, tuple[str, ...]]:
    """The one-edit neighbours split into `train`, `tune` and `heldout` words, by pronunciation group.

    A group with a word already in a fixed list keeps that list's split (`NEIGHBOURS_TRAIN`,
    `PHRASES_TRAIN` and `trained`, the sampled dictionary words: train; `OOV_TUNE`: tune;
    `OOV_HELDOUT`: held-out); the others are shuffled with `NEIGHBOUR_SEED` and cut by
    `NEIGHBOUR_FRACTIONS`. A held-out group's words are never spoken in train or tune. Train and tune
    speak every spelling of their groups (a TTS engine reads spellings differently); held-out
    speaks the group's shortest spelling."""
    fixed_train = {w for ws in NEIGHBOURS_TRAIN.values() for w in ws} | set(PHRASES_TRAIN) | trained
    fixed = (("train", fixed_train), ("tune", set(OOV_TUNE)), ("heldout", set(OOV_HELDOUT)))
    split: dict[str, list[tuple[str, ...]]] = {name: [] for name, _ in NEIGHBOUR_FRACTIONS}
    free: list[tuple[str, ...]] = []
    for group in one_edit_neighbours():
        owner = next((name for name, words in fixed if words.intersection(group)), None)
        (split[owner] if owner else free).append(group)
    random.Random(NEIGHBOUR_SEED).shuffle(free)
    start = 0
    for i, (name, frac) in enumerate(NEIGHBOUR_FRACTIONS):
        end = len(free) if i == len(NEIGHBOUR_FRACTIONS) - 1 else start + round(frac * len(free))
        split[name] += free[start:end]
        start = end
    return {
        "train": tuple(w for g in split["train"] for w in g if w not in fixed_train),
        "tune": tuple(w for g in split["tune"] for w in g if w not in OOV_TUNE),
        "heldout": tuple(g[0] for g in split["heldout"] if not set(OOV_HELDOUT).intersection(g)),
    }


ESPEAK_PHONEME_VOICES = ("en-us", "en-gb", "en-gb-x-rp", "en-gb-x-gbclan", "en-gb-x-gbcwmd")


def _espeak_phonemes(words: tuple[str, ...], voices: tuple[str, ...]) -> dict[str, tuple[str, ...]]:
    """Per voice, espeak-ng's phonemes (`-x`, stress marks removed) for each word; one call per voice,
    the voices in parallel."""
    import subprocess

    procs = {v: subprocess.Popen(["espeak-ng", "-q", "-x", "-v", v], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                 stderr=subprocess.DEVNULL, text=True) for v in voices}
    out: dict[str, tuple[str, ...]] = {}
    for v, proc in procs.items():
        lines = proc.communicate("\n".join(words) + "\n", timeout=120)[0].splitlines()
        if proc.returncode or len(lines) < len(words):
            raise RuntimeError(f"espeak-ng -x -v {v} gave {len(lines)} lines for {len(words)} words")
        out[v] = tuple(re.sub(r"[',]", "", line).strip() for line in lines[: len(words)])
    return out


@lru_cache(maxsize=8)
def _tts_homophones(words: tuple[str, ...]) -> frozenset[str]:
    phonemes = _espeak_phonemes(VOCABULARY + words, ESPEAK_PHONEME_VOICES)
    n = len(VOCABULARY)
    return frozenset(w for ph in phonemes.values() for w, p in zip(words, ph[n:], strict=True) if p in set(ph[:n]))


def tts_homophones(words: tuple[str, ...] | list[str]) -> set[str]:
    """The `words` that espeak-ng says exactly like a command in one of the training accents
    (`espeak-ng -x`, stress ignored): such a clip *is* the command, whatever its spelling."""
    return set(_tts_homophones(tuple(sorted(set(words)))))


def _edits(a: tuple[str, ...], b: tuple[str, ...]) -> int:
    prev = list(range(len(b) + 1))
    for i, x in enumerate(a, 1):
        cur = [i]
        for j, y in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (x != y)))
        prev = cur
    return prev[-1]


_VOWELS = {"AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW"}


@lru_cache(maxsize=4)
def two_edit_neighbours(per_command: int, seed: int) -> dict[str, tuple[str, ...]]:
    """Per command, `per_command` dictionary words (2-8 letters) whose pronunciation is exactly two
    phoneme edits from the command's and keeps its vowel ("no" -> slowed, blow, noting, ...; "stand" ->
    scant, ...): more negatives near the commands for training. Never a word of the tune or held-out
    lists, nor one said like any word of the tune or held-out one-edit groups, nor one of them."""
    prons = _cmudict()
    split_groups = [g for g in one_edit_neighbours()]
    edit1 = {w for g in split_groups for w in g}
    reserved = set(OOV_TUNE) | set(OOV_HELDOUT) | edit1 | forbidden_negatives()
    reserved_prons = {_phones(p) for w in reserved for p in prons.get(w, [])}
    candidates: list[tuple[str, list[tuple[str, ...]]]] = []
    for word, ps in sorted(prons.items()):
        if not (word.isalpha() and word.isascii() and 2 <= len(word) <= 8) or word in reserved:
            continue
        phs = [_phones(p) for p in ps]
        if not any(ph in reserved_prons for ph in phs):
            candidates.append((word, phs))
    out: dict[str, tuple[str, ...]] = {}
    for command in VOCABULARY:
        targets = [_phones(p) for p in prons.get(command, [])]
        vowels = {ph for t in targets for ph in t if ph in _VOWELS}
        by_pron: dict[tuple[str, ...], str] = {}
        for word, phs in candidates:
            for ph in phs:
                if (not vowels.isdisjoint(ph) and any(abs(len(ph) - len(t)) <= 2 and _edits(ph, t) == 2 for t in targets)
                        and (ph not in by_pron or len(word) < len(by_pron[ph]))):
                    by_pron[ph] = word
        words = sorted(set(by_pron.values()))
        out[command] = tuple(sorted(random.Random(f"{seed}:{command}").sample(words, min(per_command, len(words)))))
    return out


def espeak_voices(accents: tuple[str, ...], variants: tuple[str, ...]) -> list[str]:
    return [f"espeak:{a}+{v}" if v else f"espeak:{a}" for a in accents for v in variants]


def voices(split: str, recorded: tuple[str, ...] = RECORDED_TRAIN) -> list[str]:
    """The voices of `split`; `recorded`: the split's recorded speakers (train and tune: `dataset.Sizes.recorded`
    and `tune_recorded`, by default `RECORDED_TRAIN`; held-out has its own)."""
    if split == "train":
        return espeak_voices(ESPEAK_TRAIN_ACCENTS, ESPEAK_TRAIN_VARIANTS) + list(recorded)
    if split == "tune":
        return espeak_voices(ESPEAK_TRAIN_ACCENTS, ESPEAK_TUNE_VARIANTS) + list(recorded)
    if split == "heldout":
        return espeak_voices(ESPEAK_HELDOUT_ACCENTS, ESPEAK_HELDOUT_VARIANTS) + list(HELDOUT_OTHER_ENGINES)
    raise ValueError(f"unknown split {split!r}")
