"""Pseudo-words one consonant from a command: near negatives that no dictionary holds (tried on tuning data in
session 48, rule voice25: not a better curve; off in every shipped recipe).

The spotter's commonest false accepts are words one sound from a command that it never heard (a held-out "snow"
taken for "no"): the training splits hold the dictionary's one-edit neighbours of the commands, but only the
train part of them (`corpus.neighbour_split`), and real words are few near a short command. Here every command's
pronunciation (`corpus._cmudict`, stress ignored) is edited by one consonant - one inserted anywhere, one replaced
by another, or one deleted - and an edit is kept only if

- it is no word of the dictionary (so none is a tune or held-out word, nor a command or its homophone: a real word
  one edit from a command is already a one-edit neighbour, in exactly one split);
- its onset and its coda are clusters some one-syllable dictionary word begins or ends with (no "ngo", no "gow");
- it does not only voice or devoice the command's last consonant ("stob", "yez": said quickly or in noise, the
  command itself).

The vowel is the command's own, so each is spoken by espeak-ng (or an MBROLA voice through its front end) from
phonemes: the command as the voice's accent says it (`espeak-ng -x`), one consonant changed (`espeak_text`).
"""

from __future__ import annotations

import re
from functools import lru_cache

from services.voice.training import corpus, tts

CMU_TO_ESPEAK = {
    "P": "p", "B": "b", "T": "t", "D": "d", "K": "k", "G": "g", "F": "f", "V": "v", "TH": "T", "DH": "D",
    "S": "s", "Z": "z", "SH": "S", "ZH": "Z", "HH": "h", "M": "m", "N": "n", "NG": "N", "L": "l", "R": "r",
    "W": "w", "Y": "j", "CH": "tS", "JH": "dZ",
}
"""CMU consonant -> espeak-ng's phoneme mnemonic."""
VOWELS = frozenset({"AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW"})
VOICED = {"P": "B", "T": "D", "K": "G", "F": "V", "TH": "DH", "S": "Z", "SH": "ZH", "CH": "JH"}
VOICING_PAIRS = {**VOICED, **{v: k for k, v in VOICED.items()}}

Phones = tuple[str, ...]


def _syllable(phones: Phones) -> tuple[Phones, str, Phones] | None:
    """(onset, vowel, coda) of a one-syllable pronunciation; None for any other."""
    at = [i for i, p in enumerate(phones) if p in VOWELS]
    if len(at) != 1:
        return None
    i = at[0]
    return phones[:i], phones[i], phones[i + 1 :]


@lru_cache(maxsize=1)
def _dictionary() -> tuple[frozenset[Phones], frozenset[Phones], frozenset[Phones]]:
    """(every dictionary pronunciation, the onsets and the codas of its one-syllable words)."""
    prons = frozenset(corpus._phones(p) for ps in corpus._cmudict().values() for p in ps)
    onsets, codas = set(), set()
    for ph in prons:
        s = _syllable(ph)
        if s is not None:
            onsets.add(s[0])
            codas.add(s[2])
    return prons, frozenset(onsets), frozenset(codas)


def command_phones(command: str) -> Phones:
    """The command's first dictionary pronunciation, stress ignored."""
    return corpus._phones(corpus._cmudict()[command][0])


def edits(phones: Phones) -> set[Phones]:
    """Every one-consonant insertion, substitution and deletion of `phones`."""
    out: set[Phones] = set()
    for i in range(len(phones) + 1):
        out |= {phones[:i] + (c,) + phones[i:] for c in CMU_TO_ESPEAK}
    for i, p in enumerate(phones):
        if p in CMU_TO_ESPEAK:
            out |= {phones[:i] + (c,) + phones[i + 1 :] for c in CMU_TO_ESPEAK if c != p}
            out.add(phones[:i] + phones[i + 1 :])
    return out


@lru_cache(maxsize=1)
def pseudo_words() -> dict[str, tuple[Phones, ...]]:
    """Per command, its kept one-consonant edits (the module's rules), sorted."""
    prons, onsets, codas = _dictionary()  # the commands' own pronunciations among them
    out: dict[str, tuple[Phones, ...]] = {}
    for word in corpus.VOCABULARY:
        own = command_phones(word)
        last = own[-1] if own[-1] in CMU_TO_ESPEAK else None
        kept = set()
        for ph in edits(own):
            s = _syllable(ph)
            if s is None or ph in prons or s[0] not in onsets or s[2] not in codas:
                continue
            if "HH" in s[2] or ("HH" in s[0] and s[0] != ("HH",)):  # a silent or unsayable h
                continue
            if last and len(ph) == len(own) and ph[:-1] == own[:-1] and VOICING_PAIRS.get(last) == ph[-1]:
                continue
            kept.add(ph)
        out[word] = tuple(sorted(kept))
    return out


_ESPEAK_CONSONANT = re.compile(r"(tS|dZ|[pbtdkgfvTDszSZhmnNlrwj])[0-9]?")
"""A consonant in espeak-ng's phoneme string, with the variant digit some accents give it (en-us "stop": "st2'0p")."""


def _tokens(mnemonics: str) -> list[str]:
    """espeak-ng's phoneme string of one syllable as tokens: each consonant alone, everything between them (the
    stress mark and the vowel) as one token."""
    out: list[str] = []
    i, vowel = 0, ""
    while i < len(mnemonics):
        m = _ESPEAK_CONSONANT.match(mnemonics, i)
        if m is None:
            vowel += mnemonics[i]
            i += 1
            continue
        if vowel:
            out.append(vowel)
            vowel = ""
        out.append(m.group(0))
        i = m.end()
    return out + ([vowel] if vowel else [])


@lru_cache(maxsize=64)
def espeak_tokens(command: str, accent: str) -> tuple[str, ...]:
    """The command as espeak-ng's `accent` says it (`espeak-ng -x`), one token per dictionary phone, the vowel's
    with primary stress. ValueError if espeak-ng's consonants are not the dictionary's; `tts.TtsError` if espeak-ng is
    not installed."""
    said = tts._run(["espeak-ng", "-q", "-x", "-v", accent, command], package="espeak-ng").decode().strip()
    tokens = _tokens(said)
    own = command_phones(command)
    if len(tokens) != len(own) or any(
        (p in VOWELS) != (_ESPEAK_CONSONANT.fullmatch(t) is None)
        or (p not in VOWELS and t.rstrip("0123456789") != CMU_TO_ESPEAK[p])
        for p, t in zip(own, tokens, strict=False)
    ):
        raise ValueError(f"espeak-ng {accent} says {command!r} as {said!r}: not the dictionary's phones {own}")
    return tuple("'" + t.replace("'", "").replace(",", "") if p in VOWELS else t for p, t in zip(own, tokens, strict=True))


def espeak_text(phones: Phones, command: str, accent: str) -> str:
    """espeak-ng phoneme input (`[[...]]`) for `phones`, one edit of `command`: what the edit kept is said as
    `accent` says the command (its vowel with primary stress), what it changed is the consonant's plain mnemonic."""
    own, said = command_phones(command), espeak_tokens(command, accent)
    k = next((i for i, (a, b) in enumerate(zip(own, phones, strict=False)) if a != b), min(len(own), len(phones)))
    m = 0
    while m < min(len(own), len(phones)) - k and own[len(own) - 1 - m] == phones[len(phones) - 1 - m]:
        m += 1
    middle = [CMU_TO_ESPEAK[p] for p in phones[k : len(phones) - m]]
    return "[[" + "".join([*said[:k], *middle, *said[len(said) - m :]]) + "]]"


MBROLA_ACCENTS = {"us1": "en-us", "us2": "en-us", "us3": "en-us", "en1": "en-gb"}


def accent(voice: str) -> str | None:
    """The espeak-ng accent whose phonemes `voice` (a virtual speaker's too) reads; None for a voice that cannot
    read espeak-ng's phonemes."""
    engine, _, name = tts.base_voice(voice).partition(":")
    if engine == "espeak":
        return name.partition("+")[0]
    if engine == "mbrola":
        return MBROLA_ACCENTS.get(name)
    return None
