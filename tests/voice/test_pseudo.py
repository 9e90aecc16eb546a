"""Pseudo-words one consonant from a command (`training/pseudo.py`, the `pseudo` split; session 48, tuning data only)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.voice.synth import OOV_HELDOUT, OOV_TUNE
from services.voice.training import corpus, dataset, pseudo, train, tts
from tests.voice.conftest import TrainCli


def _prons(words: list[str] | tuple[str, ...]) -> set[tuple[str, ...]]:
    cmu = corpus._cmudict()
    return {corpus._phones(p) for w in words for p in cmu.get(w, [])}


def test_pseudo_words_are_one_consonant_from_their_command_and_no_word() -> None:
    words = pseudo.pseudo_words()
    assert list(words) == list(corpus.VOCABULARY) and all(words.values())
    every = {ph for ws in words.values() for ph in ws}
    prons, onsets, codas = pseudo._dictionary()
    assert not every & prons  # no dictionary word: so no tune or held-out word, command or homophone either
    split = dataset.neighbours(dataset.Sizes(), 12)
    assert not every & _prons(list(OOV_HELDOUT) + list(OOV_TUNE) + list(split["heldout"]) + list(split["tune"]))
    for command, ws in words.items():
        own = pseudo.command_phones(command)
        for ph in ws:
            assert corpus.one_edit(ph, own), (command, ph)
            assert [p for p in ph if p in pseudo.VOWELS] == [p for p in own if p in pseudo.VOWELS]  # its vowel kept
            onset, _, coda = pseudo._syllable(ph)  # type: ignore[misc]
            assert onset in onsets and coda in codas and "HH" not in coda
    assert ("K", "N", "OW") in words["no"] and ("G", "OW", "B") in words["go"]
    assert ("S", "N", "OW") not in words["no"] and ("S", "T", "AE", "N") not in words["stand"]  # snow, stan: words
    assert ("Y", "EH", "Z") not in words["yes"] and ("S", "T", "AA", "B") not in words["stop"]  # the coda voiced


def test_espeak_text_is_the_command_as_its_accent_says_it_with_one_consonant_changed() -> None:
    if tts.unavailable(["espeak:en-us"]):
        pytest.skip("espeak-ng is not installed")
    for accent in ("en-us", "en-gb"):
        for command in corpus.VOCABULARY:  # the edit that changes nothing is the command itself, sample for sample
            text = pseudo.espeak_text(pseudo.command_phones(command), command, accent)
            voice = f"espeak:{accent}+m1"
            assert np.array_equal(tts.synthesise(text, voice, 1.0, 1.0), tts.synthesise(command, voice, 1.0, 1.0))
    assert pseudo.espeak_text(("S", "N", "OW"), "no", "en-us") == "[[sn'oU]]"
    assert pseudo.espeak_text(("S", "T", "AA", "P", "S"), "stop", "en-us") == "[[st2'0ps]]"  # en-us's own t kept
    assert pseudo.espeak_text(("S", "N", "AA", "P"), "stop", "en-gb") == "[[sn'0p]]"
    assert pseudo.espeak_text(("D", "AW", "L", "N"), "down", "en-gb") == "[[d'aUln]]"
    snow = tts.synthesise("snow", "espeak:en-us+f2", 1.0, 1.0)
    assert np.array_equal(tts.synthesise("[[sn'oU]]", "espeak:en-us+f2", 1.0, 1.0), snow)


def test_only_voices_that_read_espeak_phonemes_have_an_accent() -> None:
    assert pseudo.accent("espeak:en-gb-x-rp+Mike@vtl1.1") == "en-gb-x-rp"
    assert pseudo.accent("mbrola:us2") == "en-us" and pseudo.accent("mbrola:en1@vtl0.9") == "en-gb"
    assert pseudo.accent("flite:kal16") is None and pseudo.accent("rhvoice:alan") is None
    assert pseudo.accent("kokoro:jf_alpha") is None


def test_the_pseudo_split_says_every_pseudo_word_as_often_as_asked_by_readers_only() -> None:
    sizes = dataset.with_more_recorded(replace(dataset.Sizes(), pseudo_repeats=4), "train")
    rows = dataset.recipes("pseudo", sizes, 12)
    assert len(rows) == 4 * sum(len(ws) for ws in pseudo.pseudo_words().values())
    assert {r.label for r in rows} == {dataset.OTHER}
    assert all(r.text.startswith("[[") and pseudo.accent(r.voice) is not None for r in rows)
    assert {r.voice.partition(":")[0] for r in rows} == {"espeak", "mbrola"}  # MBROLA's training voices read them
    virtual = sum("@vtl" in r.voice for r in rows)  # every other clip by a virtual speaker (some factors round to 1)
    assert 0.45 * len(rows) <= virtual <= 0.5 * len(rows)
    assert rows == dataset.recipes("pseudo", sizes, 12)
    assert "pseudo" in train.training_splits(sizes) and "pseudo" not in train.training_splits(dataset.Sizes())


def test_train_pseudo_option(train_cli: TrainCli) -> None:
    assert train_cli("--pseudo", "6", "--out", "/dev/null").exit_code == 0
    assert train_cli.recipes == [train.shipped_recipe(sizes=replace(train.shipped_recipe().sizes, pseudo_repeats=6))]
    assert train.shipped_recipe().sizes.pseudo_repeats == 0
    assert train_cli("--pseudo", "-1", "--out", "/dev/null").exit_code == 2
