"""The spotter's training corpus: one-edit neighbours of the commands, their train/tune/held-out split,
virtual speakers, the crop head and its ensemble, temperature scaling. Little speech is synthesised
here (recipes only, and one word for the vocal-tract warp)."""

from __future__ import annotations

import numpy as np
import pytest

from services.voice.spotter.features import EMBED_DIM, FRAMES
from services.voice.spotter.head import Head, HeadError
from services.voice.synth import OOV_HELDOUT, OOV_TUNE
from services.voice.training import corpus, dataset, tts
from services.voice.training.train import TrainConfig, fit, fit_temperature, speaker_splits

pytest.importorskip("pocketsphinx")  # the CMU dictionary ships in its wheel


def test_one_edit() -> None:
    go = ("G", "OW")
    assert corpus.one_edit(go, ("G", "L", "OW"))  # glow: insertion
    assert corpus.one_edit(go, ("OW",))  # owe: deletion
    assert corpus.one_edit(go, ("S", "OW"))  # so: substitution
    assert not corpus.one_edit(go, go)
    assert not corpus.one_edit(go, ("G", "OW", "L", "D"))  # gold: two edits


def test_neighbours_are_systematic_and_never_homophones() -> None:
    words = {w for group in corpus.one_edit_neighbours() for w in group}
    assert {"glow", "goat", "grow", "so", "toe", "snow", "note", "town", "sand", "top", "white"} <= words
    assert not words & corpus.forbidden_negatives()
    assert not words & {"know", "y", "wye"}


def test_heldout_neighbours_are_disjoint_from_training_and_tuning() -> None:
    sizes = dataset.Sizes()
    split = dataset.neighbours(sizes, 12)
    held = set(split["heldout"])
    assert len(held) >= 30
    assert not held & (set(split["train"]) | set(split["tune"]))
    # No spelling of a held-out neighbour's pronunciation group is trained or tuned on.
    held_groups = [set(g) for g in corpus.one_edit_neighbours() if held & set(g)]
    names = ("train", "engines", "neighbours", "positives", "tune", "neighbours-tune", "speakers-tune",
             "recorded-tune", *speaker_splits(sizes))
    spoken = {r.text for name in names for r in dataset.recipes(name, sizes, 12)}
    assert not spoken & set().union(*held_groups)
    assert not spoken & set(OOV_HELDOUT)
    assert "glow" not in spoken


def test_two_edit_words_keep_the_vowel_and_stay_out_of_tune_and_heldout() -> None:
    sizes = dataset.Sizes()
    words = corpus.two_edit_neighbours(sizes.two_edit_words, dataset.TWO_EDIT_SEED)
    prons = corpus._cmudict()
    assert set(words) == set(corpus.VOCABULARY) and all(len(ws) == sizes.two_edit_words for ws in words.values())
    for command, ws in words.items():
        targets = [corpus._phones(p) for p in prons[command]]
        for w in ws:
            assert any(corpus._edits(corpus._phones(p), t) == 2 for p in prons[w] for t in targets), (command, w)
    every = set(dataset.two_edit(sizes))
    split = dataset.neighbours(sizes, 12)
    one_edit = {w for g in corpus.one_edit_neighbours() for w in g}
    assert not every & (one_edit | set(OOV_HELDOUT) | set(OOV_TUNE) | corpus.forbidden_negatives())
    reserved = {corpus._phones(p) for w in set(split["heldout"]) | set(OOV_HELDOUT) for p in prons.get(w, [])}
    assert not {corpus._phones(p) for w in every for p in prons[w]} & reserved  # no held-out homophone either
    spoken = {r.text for r in dataset.recipes("neighbours", sizes, 12)}
    assert every - corpus.tts_homophones(list(every)) <= spoken


def test_words_espeak_says_like_a_command_are_never_negatives() -> None:
    # "wei" and "wy" are one-edit neighbours in the dictionary, but espeak-ng reads both as "why"
    assert {"wei", "wy"} <= corpus.tts_homophones(["wei", "wy", "way", "white"])
    assert not {"way", "white"} & corpus.tts_homophones(["way", "white"])
    sizes = dataset.Sizes()
    assert {"wei", "wy"} <= set(dataset.neighbours(sizes, 12)["train"])
    negatives = {r.text for name in ("neighbours", "speakers", "tune", "neighbours-tune")
                 for r in dataset.recipes(name, sizes, 12) if r.label == dataset.OTHER and r.voice}
    assert len(negatives) > 300 and not negatives & corpus.tts_homophones(list(negatives))


def test_recorded_speakers_train_and_tune_but_never_the_heldout_ones() -> None:
    sizes = dataset.Sizes()
    assert "festival:ked" in corpus.RECORDED_TRAIN and "festival:ked" in corpus.voices("train")
    recorded = dataset.recipes("recorded-tune", sizes, 12)
    by_voice = {v: sum(r.voice == v and r.label < dataset.OTHER for r in recorded) for v in corpus.RECORDED_TRAIN}
    assert by_voice == {v: sizes.recorded_tune_positives * len(corpus.VOCABULARY) for v in corpus.RECORDED_TRAIN}
    engines = {r.voice for r in dataset.recipes("engines", sizes, 12)}
    assert engines == set(corpus.RECORDED_TRAIN)
    held = set(corpus.voices("heldout")) | set(corpus.HELDOUT_EXTRA)
    assert not held & (set(corpus.voices("train")) | set(corpus.voices("tune")))
    with pytest.raises(tts.TtsError, match="unknown Festival voice"):
        tts.synthesise("stop", "festival:nobody")


def test_temperature_scaling_softens_an_over_confident_head() -> None:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(400, 4)).astype(np.float32)
    y = (x[:, 0] > 0).astype(int)
    noisy = rng.random(400) < 0.2  # a fifth of the labels disagree with the (sharp) head
    y[noisy] = 1 - y[noisy]
    head = Head(("go",), np.zeros(4, np.float32), np.ones(4, np.float32),
                [np.eye(4, dtype=np.float32), np.array([[-20, 20], [0, 0], [0, 0], [0, 0]], np.float32)],
                [np.zeros(4, np.float32), np.zeros(2, np.float32)], np.array([0.5]), np.array([0.9]))
    before = head.probabilities(x).max(axis=1).mean()
    t = fit_temperature(head, x, y)
    after = head.probabilities(x).max(axis=1).mean()
    assert t > 1.5
    assert after < before
    assert (head.probabilities(x).argmax(axis=1) == (x[:, 0] > 0)).all()  # no decision changes


def _base_voice(voice: str) -> str:
    return voice.partition(tts.VTL_MARK)[0]


def test_virtual_speakers_come_from_their_own_split_only() -> None:
    sizes = dataset.Sizes()
    heldout = set(corpus.voices("heldout"))
    for split, allowed in (("speakers", corpus.voices("train")), ("speakers:1", corpus.voices("train")),
                           ("speakers-tune", corpus.voices("tune"))):
        recipes = dataset.recipes(split, sizes, 12)
        bases = {_base_voice(r.voice) for r in recipes}
        assert bases <= set(allowed) and not bases & heldout, split
        factors = [float(r.voice.partition(tts.VTL_MARK)[2] or 1.0) for r in recipes]
        assert min(factors) >= dataset.VTL_RANGE[0] - 0.01 and max(factors) <= dataset.VTL_RANGE[1] + 0.01
        assert np.std(factors) > 0.05  # many speakers, not one
        # about half of them made from the recorded training speakers
        recorded = sum(not r.voice.startswith("espeak:") for r in recipes) / len(recipes)
        assert 0.4 < recorded < 0.65, split
    # rounds are different draws, reproducibly
    assert dataset.recipes("speakers", sizes, 12) == dataset.recipes("speakers", sizes, 12)
    assert dataset.recipes("speakers", sizes, 12)[:50] != dataset.recipes("speakers:1", sizes, 12)[:50]


def test_vocal_tract_warp_scales_frequencies_and_keeps_duration(monkeypatch: pytest.MonkeyPatch) -> None:
    sr = 16000
    t = np.arange(sr) / sr
    warped = tts.vocal_tract(np.sin(2 * np.pi * 1000 * t), 1.2)
    peak = np.fft.rfftfreq(warped.size, 1 / sr)[np.argmax(np.abs(np.fft.rfft(warped)))]
    assert abs(peak - 1200) < 5 and abs(warped.size - sr / 1.2) < 2
    # A virtual speaker: the engine speaks slower and lower by the factor, then every frequency is
    # raised by it, so the speaker's pitch and duration come out as asked and only the formants move.
    calls = []

    def engine(text: str, name: str, speed: float, pitch: float) -> np.ndarray:
        calls.append((name, speed, pitch))
        n = int(0.5 * speed * sr)
        return np.sin(2 * np.pi * 120 * pitch * np.arange(n) / sr)

    monkeypatch.setitem(tts.ENGINES, "espeak", engine)
    x = tts.synthesise("no", "espeak:en-us+f1@vtl1.20", speed=1.1, pitch=0.9)
    assert calls == [("en-us+f1", pytest.approx(1.1 * 1.2), pytest.approx(0.9 / 1.2))]
    assert abs(x.size - 0.5 * 1.1 * sr) < 0.01 * sr
    f0 = np.fft.rfftfreq(x.size, 1 / sr)[np.argmax(np.abs(np.fft.rfft(x)))]
    assert abs(f0 - 120 * 0.9) < 3
    assert tts.virtual_speaker("flite:awb", 1.0) == "flite:awb"
    with pytest.raises(tts.TtsError, match="outside"):
        tts.synthesise("stop", "espeak:en-us@vtl3.0")
    with pytest.raises(tts.TtsError, match="bad vocal-tract"):
        tts.synthesise("stop", "espeak:en-us@vtlx")


def _toy_data(n: int = 240) -> tuple[np.ndarray, np.ndarray]:
    """Eight classes told apart by which embedding dimension is raised in the middle frames."""
    rng = np.random.default_rng(1)
    y = np.arange(n) % (len(corpus.VOCABULARY) + 1)
    x = rng.normal(0, 0.3, (n, FRAMES, EMBED_DIM)).astype(np.float32)
    x[np.arange(n), 6:10, y] += 2.0
    return x, y


def test_crop_ensemble_head_round_trips_and_classifies(tmp_path) -> None:
    x, y = _toy_data()
    cfg = TrainConfig(hidden=8, ensemble=2, crop_width=8, crop_starts=(2, 4, 6))
    head = fit(x, y, cfg)
    assert head.weights[0].shape == (8 * EMBED_DIM, 16)  # two members of 8 hidden units side by side
    assert (head.probabilities(x).argmax(axis=1) == y).mean() > 0.95
    # shifting the word by one frame changes little: the crops see it anyway
    assert (head.probabilities(np.roll(x, 1, axis=1)).argmax(axis=1) == y).mean() > 0.9
    path = tmp_path / "head.npz"
    head.save(path)
    back = Head.load(path)
    assert (back.crop_width, back.crop_starts) == (8, (2, 4, 6))
    np.testing.assert_allclose(back.probabilities(x), head.probabilities(x), atol=2e-3)  # float16 weights
    # the flattened input (as enrolment passes it) gives the same answer
    np.testing.assert_allclose(back.hidden(x.reshape(len(x), -1)), back.hidden(x), atol=1e-5)


def test_crops_that_do_not_fit_are_refused(tmp_path) -> None:
    x, y = _toy_data()
    head = fit(x, y, TrainConfig(hidden=4, ensemble=1, crop_width=8, crop_starts=(2, 6)))
    head.crop_starts = (2, 12)  # 12 + 8 > 16 frames
    path = tmp_path / "head.npz"
    head.save(path)
    with pytest.raises(HeadError, match="crops"):
        Head.load(path)


def test_the_fits_run_on_the_pinned_blas_thread_count_whatever_the_caller_set(monkeypatch) -> None:
    """The rounding of the fits depends on how BLAS splits the products: one thread instead of two gave
    another head. `fit` pins the count even inside a caller's lower limit (OPENBLAS_NUM_THREADS=1 does the
    same), so the core count of the machine that trains does not change the head."""
    from sklearn.neural_network import MLPClassifier
    from threadpoolctl import threadpool_info, threadpool_limits

    if not any(i["user_api"] == "blas" for i in threadpool_info()):
        pytest.skip("no BLAS library that threadpoolctl can see")
    seen: list[set[int]] = []
    real_fit = MLPClassifier.fit

    def recording_fit(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        seen.append({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})
        return real_fit(self, *args, **kwargs)

    monkeypatch.setattr(MLPClassifier, "fit", recording_fit)
    x, y = _toy_data()
    with threadpool_limits(limits=1, user_api="blas"):
        fit(x, y, TrainConfig(hidden=4, ensemble=2, crop_width=8, crop_starts=(2, 6), blas_threads=2))
        assert {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"} == {1}  # restored
    assert seen == [{2}, {2}]


def test_enrolment_prompt_words_follow_their_rule_and_are_no_tune_or_heldout_word() -> None:
    """enrol.PROMPT_OTHERS: per command the first two words of NEIGHBOURS_TRAIN (listed order) that are one word,
    spell no command and are no tune or held-out word; none shares a pronunciation with a tune or held-out word
    (so enrolment never says a word the tuning proxy or the bench scores)."""
    from services.voice.enrol import PROMPT_OTHERS

    split = dataset.neighbours(dataset.Sizes(), 12)
    reserved = set(OOV_TUNE) | set(OOV_HELDOUT) | set(split["tune"]) | set(split["heldout"]) | corpus.forbidden_negatives()
    expected = []
    for command in corpus.VOCABULARY:
        expected += [w for w in corpus.NEIGHBOURS_TRAIN[command]
                     if w.isalpha() and w not in reserved and not any(c in w for c in corpus.VOCABULARY)][:2]
    assert PROMPT_OTHERS == tuple(expected)
    prons = corpus._cmudict()
    said = {corpus._phones(p) for w in reserved | set(corpus.VOCABULARY) for p in prons.get(w, [])}
    assert all(w in prons for w in PROMPT_OTHERS)
    assert not {corpus._phones(p) for w in PROMPT_OTHERS for p in prons[w]} & said
