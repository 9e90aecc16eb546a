"""Recipes for every training / tuning clip, and their rendering into spotter features.

A recipe says what is said (or which noise), by which voice, at which speed and pitch, with which
augmentation seed; rendering runs the same path as the service (`trim_to_speech`, then the spotter's
`Embedder.utterance`). Features are cached under the synth cache folder, keyed by the recipes, so a
second `train` run only fits the head; the mel spectrograms they were computed from are cached with them
(float16, `indexed_mels`), for mel-level variants that need only the embedding pass. Nothing here is committed.
"""

from __future__ import annotations

import functools
import hashlib
import json
import multiprocessing
import os
import random
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import cast

import numpy as np

from services.runtime import get_logger
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.sources import trim_to_speech
from services.voice.spotter import whisper
from services.voice.spotter.embedders import SPEECH_EMBEDDING, UtteranceEmbedder, embedder_for
from services.voice.spotter.features import FRAMES, MAX_SPEECH_S, Embedder, speech_seconds
from services.voice.synth import OOV_TUNE, cache_dir, noise
from services.voice.training import augment, corpus, tts

DATASET_VERSION = 2
OTHER = len(corpus.VOCABULARY)
NOISES = ("white", "pink", "brown", "hum", "clicks")


@dataclass(frozen=True)
class Recipe:
    text: str
    """Words to speak; for a noise clip, the noise kind."""
    label: int
    voice: str = ""
    """`engine:name`; empty for pure noise."""
    speed: float = 1.0
    pitch: float = 1.0
    seed: int = 0
    strength: float = 1.0
    """Augmentation strength (0: clean)."""
    far: float = 0.0
    """Chance that the clip is said from further away (`augment.far`; round voice39's `Sizes.far`); 0: never."""


@dataclass(frozen=True)
class Sizes:
    positives: int = 450
    """Per command word, train split."""
    neighbour_repeats: int = 6
    common_words: int = 600
    common_repeats: int = 4
    phrase_repeats: int = 8
    noise: int = 400
    tune_positives: int = 80
    tune_common_words: int = 300
    engines_positives: int = 300
    """Per command, `engines` split: the recorded training voices (`corpus.RECORDED_TRAIN`, 100 each)."""
    engines_repeats: int = 2
    neighbour_repeats_all: int = 4
    """Per train one-edit neighbour (`corpus.neighbour_split`), `neighbours` split, any training voice."""
    neighbour_repeats_engines: int = 2
    """And again with the non-espeak training voices only."""
    tune_neighbour_repeats: int = 4
    more_positives: int = 300
    """Per command, `positives` split: more command clips by the training voices (other draws), so
    that the one-edit neighbours do not outnumber the commands."""
    speaker_positives: int = 320
    """Per command, `speakers` split: virtual speakers (`tts.vocal_tract`) made from the training voices,
    half of them from the two recorded (flite) training speakers."""
    speaker_neighbour_repeats: int = 3
    """Per train one-edit neighbour and per hand-picked neighbour, `speakers` split."""
    speaker_common_repeats: int = 1
    speaker_rounds: int = 2
    """`speakers` splits: `speakers`, `speakers:1`, ... (each its own draws, cached on its own)."""
    tune_speaker_positives: int = 40
    """Per command, `speakers-tune`: virtual speakers of the tune voices (with the tune neighbours)."""
    tune_speaker_neighbour_repeats: int = 2
    two_edit_words: int = 40
    """Per command, words two phoneme edits from it (`corpus.two_edit_neighbours`), train only."""
    two_edit_repeats: int = 3
    """Per two-edit word in `neighbours` (any training voice), plus one by a recorded voice and one per
    round of `speakers`."""
    foreign_positives: int = 0
    """Per command, `foreign` split (round 11): the recorded speakers of other languages (`corpus.FOREIGN_TRAIN`)
    saying it; 0 (the committed recipe): no `foreign` split is fitted on."""
    foreign_neighbour_repeats: int = 1
    """Per hand-picked neighbour and per foreign voice, and per train one-edit neighbour, two-edit word and
    sampled dictionary word (by one foreign voice drawn at random), `foreign` split."""
    neural_positives: int = 0
    """Per command, `neural` split: virtual speakers made from Kokoro's three training voices (`corpus.NEURAL_TRAIN`,
    a neural TTS) saying it; 0 (the committed recipe): no `neural` split is fitted on."""
    neural_repeats: int = 1
    """Per hand-picked neighbour, train one-edit neighbour, two-edit word and sampled dictionary word, `neural`."""
    pseudo_repeats: int = 0
    """Per pseudo-word one consonant from a command (`pseudo.pseudo_words`), `pseudo` split: espeak-ng's training
    voices and the recorded speakers that read its phonemes (MBROLA's), half as virtual speakers; 0 (the committed
    recipe): no `pseudo` split is fitted on (tried on tuning data only, rule voice25: not a better curve)."""
    far: float = 0.0
    """Share of every split's speech clips said from further away (round voice39, `train --far`): a peak of -48 to
    -26 dBFS over a microphone's hiss (`augment.far`); 0 (the committed recipe): none."""
    far_tune: bool = True
    """Whether `far` applies to the tune splits too (round voice39); False (round voice39b, `train --far-where
    train`): only to the splits the head is fitted on, so the knots are placed on the same near tune speech as
    without it."""
    recorded_tune_positives: int = 30
    """Per command and per recorded training voice, `recorded-tune` (with the tune non-commands): the
    tune figures per recorded speaker, and a leave-one-speaker-out check of the recipe."""
    recorded: tuple[str, ...] = corpus.RECORDED_TRAIN
    """The recorded speakers of the training splits (`corpus.voices`): `engines` and half the virtual speakers are
    theirs (`with_more_recorded`; the default head's recipe adds `corpus.RECORDED_MORE` here)."""
    tune_recorded: tuple[str, ...] = corpus.RECORDED_TRAIN
    """The recorded speakers of the tune splits (`tune`, `neighbours-tune`, `speakers-tune`, `recorded-tune`), which
    place the knots."""


MORE_VOICES = ("off", "train", "train+tune", "train+gb")
"""`train --more-voices`: where `corpus.RECORDED_MORE` speak (`with_more_recorded`); "train+gb" adds `corpus.RECORDED_GB`
to them (round voice29)."""


def with_more_recorded(sizes: Sizes, where: str) -> Sizes:
    """`sizes` with `corpus.RECORDED_MORE` among the recorded speakers of the training splits, the `engines` split
    grown with them so that each recorded speaker says as many commands and other words there as before (100 clips
    per command); with `where` "train+tune" (round voice19) of the tune splits too, with "train" (round voice19b)
    not: the knots are then placed on the same tune speech as before; with "train+gb" (round voice29) as "train", with
    `corpus.RECORDED_GB` after them. ValueError for another `where`."""
    if where not in MORE_VOICES:
        raise ValueError(f"{where!r}: one of {', '.join(MORE_VOICES)}")
    if where == "off":
        return sizes
    more = corpus.RECORDED_MORE + (corpus.RECORDED_GB if where == "train+gb" else ())
    recorded = sizes.recorded + tuple(v for v in more if v not in sizes.recorded)
    grow = len(recorded) / len(sizes.recorded)
    tune = recorded if where == "train+tune" else sizes.tune_recorded
    return replace(sizes, recorded=recorded, tune_recorded=tune, engines_positives=round(sizes.engines_positives * grow),
                   engines_repeats=round(sizes.engines_repeats * grow))


VTL_RANGE = (0.84, 1.22)
"""Vocal-tract factors of virtual speakers (log-uniform): about the spread of adult speakers' formants,
men to women, around a synthesiser's speaker."""


def _voice_draw(rng: random.Random, voices: list[str]) -> tuple[str, float, float]:
    return rng.choice(voices), rng.uniform(0.75, 1.35), rng.uniform(0.7, 1.5)


def _speaker_draw(rng: random.Random, voices: list[str]) -> tuple[str, float, float]:
    """A virtual speaker: half the time one of the recorded (non-espeak) voices, then a vocal-tract
    factor; pitch is drawn independently of it (a narrower range: the factor already moves formants)."""
    recorded = [v for v in voices if not v.startswith("espeak:")]
    voice = rng.choice(recorded if recorded and rng.random() < 0.5 else voices)
    factor = float(np.exp(rng.uniform(np.log(VTL_RANGE[0]), np.log(VTL_RANGE[1]))))
    return tts.virtual_speaker(voice, factor), rng.uniform(0.8, 1.3), rng.uniform(0.8, 1.3)


TWO_EDIT_SEED = 7


def two_edit(sizes: Sizes) -> list[str]:
    words = corpus.two_edit_neighbours(sizes.two_edit_words, TWO_EDIT_SEED)
    return sorted({w for ws in words.values() for w in ws})


def neighbours(sizes: Sizes, seed: int) -> dict[str, tuple[str, ...]]:
    """The one-edit neighbours of the commands split into train / tune / held-out words, the
    dictionary words sampled for training counted as train."""
    pool = corpus.common_words(sizes.common_words + sizes.tune_common_words, seed)
    return corpus.neighbour_split(frozenset(pool))


def recipes(split: str, sizes: Sizes, seed: int) -> list[Recipe]:
    """Every clip of the `train`, `engines`, `neighbours`, `positives`, `speakers`, `tune`, `neighbours-tune`
    or `speakers-tune` split (the held-out split belongs to the bench).

    `speakers` and `speakers-tune` are said by virtual speakers (`_speaker_draw`, `tts.vocal_tract`).

    `neighbours` and `neighbours-tune` speak the train and tune one-edit neighbours of the commands
    (`corpus.neighbour_split`: glow, goat, so, ... for "go"); `neighbours` and `speakers` also the
    two-edit words (`two_edit`). `engines` adds clips of the recorded training voices
    (`corpus.RECORDED_TRAIN`: flite kal16 and awb, Festival ked): in `train` they are 3 of 178 voices,
    and espeak-ng alone does not teach what speech made from recordings sounds like. `recorded-tune`:
    the recorded voices (not warped) saying the commands and the tune non-commands. `foreign` (only fitted on
    when `Sizes.foreign_positives` > 0): recorded speakers of other languages (`corpus.FOREIGN_TRAIN`) saying
    the commands and the training negatives. `neural` (only fitted on when `Sizes.neural_positives` > 0, round
    voice22): a neural TTS, Kokoro's three training voices (`corpus.NEURAL_TRAIN`) as virtual speakers, saying the
    commands and the training negatives. `pseudo` (only fitted on when `Sizes.pseudo_repeats` > 0; session 48):
    pseudo-words one consonant from a command (`pseudo`), said from phonemes by the training voices that read them.

    A non-command that espeak-ng says exactly like a command (`corpus.tts_homophones`) is left out."""
    rng = random.Random(f"{seed}:{split}")
    kind = split.partition(":")[0]  # speakers:1 is another round of speakers
    tune_split = kind in ("tune", "neighbours-tune", "speakers-tune", "recorded-tune")
    if split == "foreign":
        voices = list(corpus.FOREIGN_TRAIN)
    elif split == "neural":
        voices = list(corpus.NEURAL_TRAIN)
    else:
        side = "tune" if tune_split else "train"
        voices = corpus.voices(side, sizes.tune_recorded if side == "tune" else sizes.recorded)
    if split in ("engines", "recorded-tune"):
        voices = [v for v in voices if not v.startswith("espeak:")]
    pool = corpus.common_words(sizes.common_words + sizes.tune_common_words, seed)
    out: list[Recipe] = []
    draw = _speaker_draw if split.startswith("speakers") or split == "neural" else _voice_draw

    said_as_command = corpus.tts_homophones(
        [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws] + list(corpus.PHRASES_TRAIN) + pool
        + list(corpus.neighbour_split(frozenset(pool))["train"]) + list(corpus.neighbour_split(frozenset(pool))["tune"])
        + list(OOV_TUNE) + two_edit(sizes))

    def add(text: str, label: int, n: int, strength_clean: float = 0.2, among: list[str] | None = None) -> None:
        """`n` clips of `text`, each by a voice drawn from `among` (default: the split's voices)."""
        if label == OTHER and text in said_as_command:
            return
        for _ in range(n):
            v, s, p = draw(rng, among or voices)
            strength = 0.0 if rng.random() < strength_clean else 1.0
            out.append(Recipe(text, label, v, round(s, 3), round(p, 3), rng.randrange(2**31), strength))

    def add_commands(n: int) -> None:
        for i, word in enumerate(corpus.VOCABULARY):
            add(word, i, n)

    if split == "train":
        add_commands(sizes.positives)
        negatives = [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws]
        for word in negatives:
            add(word, OTHER, sizes.neighbour_repeats)
        for word in pool[: sizes.common_words]:
            add(word, OTHER, sizes.common_repeats)
        for phrase in corpus.PHRASES_TRAIN:
            add(phrase, OTHER, sizes.phrase_repeats)
        n_noise = sizes.noise
    elif split == "engines":
        add_commands(sizes.engines_positives)
        for word in [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws] + list(corpus.PHRASES_TRAIN):
            add(word, OTHER, sizes.engines_repeats)
        for word in pool[: sizes.common_words]:
            add(word, OTHER, sizes.engines_repeats)
        n_noise = 0
    elif split == "foreign":
        add_commands(sizes.foreign_positives)
        for voice in corpus.FOREIGN_TRAIN:  # the hand-picked neighbours by every foreign voice
            for word in [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws]:
                add(word, OTHER, sizes.foreign_neighbour_repeats, among=[voice])
        for word in list(neighbours(sizes, seed)["train"]) + two_edit(sizes) + pool[: sizes.common_words]:
            add(word, OTHER, sizes.foreign_neighbour_repeats)
        n_noise = 0
    elif split == "neural":  # virtual speakers of the three voices (`_speaker_draw`: a vocal-tract factor each)
        add_commands(sizes.neural_positives)
        hand_picked = [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws]
        for word in hand_picked + list(neighbours(sizes, seed)["train"]) + two_edit(sizes) + pool[: sizes.common_words]:
            add(word, OTHER, sizes.neural_repeats)
        n_noise = 0
    elif split == "pseudo":  # pseudo-words one consonant from a command, from phonemes (`pseudo`)
        from services.voice.training import pseudo

        readers = [v for v in voices if pseudo.accent(v) is not None]
        for command, words in pseudo.pseudo_words().items():
            for phones in words:
                for k in range(sizes.pseudo_repeats):
                    v, s, p = (_speaker_draw if k % 2 else _voice_draw)(rng, readers)
                    text = pseudo.espeak_text(phones, command, cast(str, pseudo.accent(v)))
                    strength = 0.0 if rng.random() < 0.2 else 1.0
                    out.append(Recipe(text, OTHER, v, round(s, 3), round(p, 3), rng.randrange(2**31), strength))
        n_noise = 0
    elif split == "positives":
        add_commands(sizes.more_positives)
        n_noise = 0
    elif split in ("neighbours", "neighbours-tune"):
        words = neighbours(sizes, seed)["train" if split == "neighbours" else "tune"]
        for word in words:
            add(word, OTHER, sizes.neighbour_repeats_all if split == "neighbours" else sizes.tune_neighbour_repeats)
        if split == "neighbours":
            for word in two_edit(sizes):
                add(word, OTHER, sizes.two_edit_repeats)
            voices = [v for v in voices if not v.startswith("espeak:")]
            for word in words:
                add(word, OTHER, sizes.neighbour_repeats_engines)
            for word in two_edit(sizes):
                add(word, OTHER, 1)
        n_noise = 0
    elif kind == "speakers":
        add_commands(sizes.speaker_positives)
        hand_picked = [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws]
        for word in hand_picked + list(neighbours(sizes, seed)["train"]):
            add(word, OTHER, sizes.speaker_neighbour_repeats)
        for word in pool[: sizes.common_words]:
            add(word, OTHER, sizes.speaker_common_repeats)
        for word in two_edit(sizes):
            add(word, OTHER, 1)
        n_noise = 0
    elif split == "speakers-tune":
        add_commands(sizes.tune_speaker_positives)
        for word in neighbours(sizes, seed)["tune"]:
            add(word, OTHER, sizes.tune_speaker_neighbour_repeats)
        n_noise = 0
    elif split == "recorded-tune":
        for voice in tuple(voices):
            voices = [voice]
            add_commands(sizes.recorded_tune_positives)
            for word in OOV_TUNE:
                add(word, OTHER, 3)
            for word in neighbours(sizes, seed)["tune"]:
                add(word, OTHER, 1)
        n_noise = 0
    elif split == "tune":
        add_commands(sizes.tune_positives)
        forbidden = corpus.forbidden_negatives()
        for word in OOV_TUNE:
            if word not in forbidden:
                add(word, OTHER, 6)
        for word in pool[sizes.common_words :]:
            add(word, OTHER, 1)
        n_noise = sizes.noise // 4
    else:
        raise ValueError(f"recipes are for train or tune, not {split!r}")
    for _ in range(n_noise):
        out.append(Recipe(rng.choice(NOISES), OTHER, seed=rng.randrange(2**31)))
    far = sizes.far if sizes.far_tune or not tune_split else 0.0
    return [replace(r, far=far) if r.voice else r for r in out] if far else out


_EMBEDDERS: dict[str, UtteranceEmbedder] = {}


def _embedder(name: str = SPEECH_EMBEDDING) -> UtteranceEmbedder:
    """This process's embedder `name` (one per rendering process)."""
    if name not in _EMBEDDERS:
        _EMBEDDERS[name] = embedder_for(name)
    return _EMBEDDERS[name]


def render(r: Recipe) -> bytes | None:
    """The recipe's audio as the service would receive it (trimmed to speech), or None if it is too
    long to be one command word (the spotter rejects those before the classifier)."""
    pcm = render_utterance(r)
    return None if speech_seconds(pcm) > MAX_SPEECH_S else pcm


def render_utterance(r: Recipe) -> bytes:
    """The recipe's audio, trimmed to its speech as the service trims a WAV file."""
    rng = np.random.default_rng(r.seed)
    if not r.voice:
        level = 10 ** rng.uniform(-3.0, -0.7)
        x = noise(r.text, int(rng.uniform(0.6, 2.5) * SAMPLE_RATE), rng) * level
    else:
        speech = tts.synthesise(r.text, r.voice, r.speed, r.pitch)
        aug = augment.Augment.draw(rng, r.strength)
        if r.far:  # its own generator: the clip's other draws stay the ones a near clip makes
            aug = augment.far(aug, np.random.default_rng([r.seed, 39]), r.far)
        others: list[np.ndarray] = []
        if aug.noise == "babble":
            others = [tts.synthesise(w, r.voice, 1.0, 1.0) * rng.uniform(0.3, 1.0)
                      for w in rng.choice(["table", "water", "music", "window", "morning"], 3)]
        x = augment.apply(speech, aug, rng, others)
    return trim_to_speech(to_pcm(x))


def _features(r: Recipe, embedding: str = SPEECH_EMBEDDING) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The recipe's embeddings (float16; for the speech embedding (FRAMES, 96), with the mel spectrogram
    they were computed from, float16, the embeddings computed from the float32 spectrogram; for another
    embedding, no spectrogram), or None if it does not render."""
    try:
        pcm = render(r)
    except tts.TtsError:
        return None
    if pcm is None:
        return None
    if embedding != SPEECH_EMBEDDING:
        return _embedder(embedding).utterance(pcm, seed=r.seed).astype(np.float16), None
    emb = cast(Embedder, _embedder())
    spec = emb.utterance_mel(pcm, seed=r.seed)
    return emb.embed_mel(spec)[:FRAMES].astype(np.float16), spec.astype(np.float16)


def _recorded(r: Recipe) -> dict[str, object]:
    """The recipe's fields as its cache key hashes them: `far` only when set, so that every cache made before the
    field existed keeps its key."""
    fields = asdict(r)
    if not r.far:
        del fields["far"]
    return fields


def _key(items: list[Recipe]) -> str:
    blob = json.dumps([DATASET_VERSION] + [_recorded(r) for r in items], sort_keys=True).encode()
    return hashlib.sha1(blob).hexdigest()[:16]


WHISPER_NAMES = (whisper.NAME, whisper.FINE_NAME)


def _cache_path(kind: str, items: list[Recipe], embedding: str = SPEECH_EMBEDDING) -> Path:
    """Where the `kind` ("features" or "mels") of these recipes are cached (another embedding's features:
    `features-<embedding>`). Whisper's features are named by the arithmetic that made them, which gives other numbers
    (`spotter.whisper`): `-float32` (`HRI_VOICE_WHISPER_COMPUTE=float32`), `-int8-exact` (int8 on a CPU with VNNI) or
    `-int8-saturating` (int8 on an x86 CPU without), so a cache folder shared by machines of both kinds
    (`HRI_VOICE_CACHE`) never hands one kind's features to the other."""
    if embedding != SPEECH_EMBEDDING:
        kind = f"{kind}-{embedding}"
        if embedding in WHISPER_NAMES:
            arithmetic = whisper.compute_type()
            if arithmetic == "int8":
                arithmetic = "int8-exact" if whisper.exact_int8() else "int8-saturating"
            kind = f"{kind}-{arithmetic}"
    return cache_dir() / f"spotter-{kind}-{_key(items)}.npz"


def _cached(kind: str, items: list[Recipe], workers: int, progress: bool,
            embedding: str = SPEECH_EMBEDDING) -> np.lib.npyio.NpzFile:
    """The cached `kind` of these recipes, rendering them all first if it is not cached yet."""
    path = _cache_path(kind, items, embedding)
    if not path.exists():
        _render_all(items, workers, progress, embedding)
    return np.load(path)


def _save(path: Path, **arrays: np.ndarray) -> None:
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")  # two processes (pytest's workers) may fill the cache at once
    np.savez_compressed(tmp, **arrays)  # type: ignore[arg-type]
    tmp.replace(path)


def _render_all(items: list[Recipe], workers: int, progress: bool, embedding: str = SPEECH_EMBEDDING) -> None:
    """Render and embed every recipe once; cache the features and (speech embedding, float16) the mel
    spectrograms."""
    tts.require(r.voice for r in items)
    xs: list[np.ndarray] = []
    mels: list[np.ndarray] = []
    ys: list[int] = []
    kept: list[int] = []
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(workers) as pool:
        work = functools.partial(_features, embedding=embedding)
        for i, (r, f) in enumerate(zip(items, pool.imap(work, items, chunksize=16), strict=True)):
            if f is not None:
                xs.append(f[0])
                if f[1] is not None:
                    mels.append(f[1])
                ys.append(r.label)
                kept.append(i)
            if progress and (i + 1) % 500 == 0:
                get_logger("voice.train").info("features", done=i + 1, clips=len(items))
    y, idx = np.asarray(ys, dtype=np.int16), np.asarray(kept, dtype=np.int32)
    features_path = _cache_path("features", items, embedding)
    if not features_path.exists():  # rendering is deterministic: an existing file holds the same numbers
        _save(features_path, x=np.stack(xs), y=y, idx=idx)
    if mels:
        _save(_cache_path("mels", items), mel=np.stack(mels), y=y, idx=idx)


def features(items: list[Recipe], workers: int = 2, progress: bool = True,
             embedding: str = SPEECH_EMBEDDING) -> tuple[np.ndarray, np.ndarray]:
    """(X: n x FRAMES x 96 float16, or the other embedding's shape, y: n) for the recipes that render; cached."""
    x, y, _ = indexed_features(items, workers, progress, embedding)
    return x, y


def indexed_features(items: list[Recipe], workers: int = 2, progress: bool = True,
                     embedding: str = SPEECH_EMBEDDING) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`features` and, for each row, the index of its recipe in `items`. Rendering them with the speech
    embedding also caches their mel spectrograms (`indexed_mels`)."""
    data = _cached("features", items, workers, progress, embedding)
    return data["x"], data["y"], data["idx"]


def split_rows(splits: tuple[str, ...], sizes: Sizes, seed: int, workers: int = 2, progress: bool = True,
               embedding: str = SPEECH_EMBEDDING) -> tuple[np.ndarray, np.ndarray, list[Recipe], list[str]]:
    """The features and labels of these splits, one after another (`indexed_features`, cached), with each row's
    recipe and split name."""
    xs, ys, rows, names = [], [], [], []
    for split in splits:
        items = recipes(split, sizes, seed)
        x, y, idx = indexed_features(items, workers, progress, embedding)
        xs.append(x)
        ys.append(y)
        rows += [items[i] for i in idx]
        names += [split] * len(y)
    return np.concatenate(xs), np.concatenate(ys), rows, names


def indexed_mels(items: list[Recipe], workers: int = 2,
                 progress: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(mel spectrograms: n x mel frames x 32 float16, y, recipe index) of the rows `indexed_features`
    gives, as `Embedder.utterance_mel` computes them (mel / 10 + 2, the centred window), cached (~13 KB
    a clip). For mel-level variants: transform them and embed with `Embedder.embed_mel(...)[:FRAMES]`,
    without re-rendering the audio. Features cached before this cache existed are rendered again once."""
    data = _cached("mels", items, workers, progress)
    return data["mel"], data["y"], data["idx"]

