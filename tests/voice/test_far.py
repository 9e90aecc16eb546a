"""Far voices in the training data (`train --far`, round voice39): `augment.far`, `augment.hiss`, `Sizes.far`.
Rendering uses espeak-ng (a system package the tests install); no model is loaded."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.signal import welch

from services.voice.audio import SAMPLE_RATE
from services.voice.training import augment, dataset
from services.voice.training.dataset import OTHER, Recipe, Sizes
from tests.voice.conftest import TrainCli


def dbfs(x: np.ndarray) -> float:
    return float(20 * np.log10(np.max(np.abs(x))))


def test_far_changes_only_the_peak_and_the_hiss_and_only_at_its_share() -> None:
    draws = [augment.Augment.draw(np.random.default_rng(s)) for s in range(200)]
    assert all(augment.far(a, np.random.default_rng(s), 0.0) == a for s, a in enumerate(draws))
    far = [augment.far(a, np.random.default_rng(s), 1.0) for s, a in enumerate(draws)]
    lo, hi = augment.FAR_PEAK_DBFS
    assert all(lo <= 20 * np.log10(f.peak) <= hi for f in far)
    floors = [f.floor_dbfs for f in far if f.floor_dbfs is not None]
    assert len(floors) == len(far) and all(augment.FAR_FLOOR_DBFS[0] <= v <= augment.FAR_FLOOR_DBFS[1] for v in floors)
    assert all(replace(f, peak=a.peak, floor_dbfs=None) == a for f, a in zip(far, draws, strict=True))
    taken = sum(augment.far(a, np.random.default_rng(s), 0.3) != a for s, a in enumerate(draws))
    assert 40 <= taken <= 80  # about 60 of 200


def test_the_hiss_is_at_its_level_and_has_little_above_the_converter_filter() -> None:
    x = augment.hiss(4 * SAMPLE_RATE, -70.0, np.random.default_rng(1))
    assert abs(20 * np.log10(np.sqrt(np.mean(x**2))) + 70.0) < 0.01
    f, p = welch(x, fs=SAMPLE_RATE, nperseg=1024)
    assert p[f > 7800].mean() < 0.05 * p[(f > 1000) & (f < 6000)].mean()
    quiet = augment.apply(np.zeros(SAMPLE_RATE), replace(augment.Augment(), pad_s=(0.0, 0.0), floor_dbfs=-66.0),
                          np.random.default_rng(2))
    assert abs(20 * np.log10(np.sqrt(np.mean(quiet**2))) + 66.0) < 0.1  # over the 16-bit dither, which is ~-84


def test_sizes_far_marks_the_speech_clips_of_every_split_and_nothing_else() -> None:
    near = dataset.recipes("tune", Sizes(), 12)
    far = dataset.recipes("tune", replace(Sizes(), far=0.3), 12)
    assert [replace(r, far=0.0) for r in far] == near
    assert {r.far for r in far if r.voice} == {0.3} and {r.far for r in far if not r.voice} == {0.0}
    assert any(not r.voice for r in far)


def test_far_where_train_leaves_the_tune_splits_near() -> None:
    """Round voice39b: with `far_tune` off the knots are placed on the tune speech a head without far voices has."""
    train_only = replace(Sizes(), far=0.3, far_tune=False)
    for split in ("tune", "neighbours-tune", "speakers-tune", "recorded-tune"):
        assert dataset.recipes(split, train_only, 12) == dataset.recipes(split, Sizes(), 12), split
    for split in ("positives", "engines"):
        fitted = dataset.recipes(split, train_only, 12)
        assert fitted == dataset.recipes(split, replace(Sizes(), far=0.3), 12), split
        assert {r.far for r in fitted if r.voice} == {0.3}, split


def test_train_far_where_option(train_cli: TrainCli) -> None:
    assert train_cli("--far", "0.3", "--far-where", "train", "--out", "/dev/null").exit_code == 0
    assert train_cli("--far", "0.3", "--out", "/dev/null").exit_code == 0
    refused = train_cli("--far", "0.3", "--far-where", "tune", "--out", "/dev/null")
    assert refused.exit_code == 2 and len(train_cli.recipes) == 2  # refused before any training
    assert [cfg.sizes.far_tune for cfg in train_cli.recipes] == [False, True]
    assert {cfg.sizes.far for cfg in train_cli.recipes} == {0.3}


def test_a_cache_made_before_far_existed_is_still_found() -> None:
    items = [Recipe("stop", 5, "espeak:en-us", 1.0, 1.0, 7, 0.0), Recipe("white", OTHER, seed=3)]
    assert dataset._key(items) == "fc2019df4fd1e2a1"  # the key these recipes had before the field was added
    assert dataset._key([replace(items[0], far=0.3), items[1]]) != dataset._key(items)


def test_a_far_clip_is_quiet_and_its_other_draws_are_a_near_clips() -> None:
    r = Recipe("stop", 5, "espeak:en-us", 1.0, 1.0, 7, 0.0)
    near = np.frombuffer(dataset.render_utterance(r), np.int16) / 32768
    never = np.frombuffer(dataset.render_utterance(replace(r, far=1e-12)), np.int16) / 32768
    np.testing.assert_array_equal(never, near)  # the share's own draw changes nothing else
    far = np.frombuffer(dataset.render_utterance(replace(r, far=1.0)), np.int16) / 32768
    assert dbfs(near) > -26.5 and -49.0 < dbfs(far) < -25.0
    noise = Recipe("white", OTHER, seed=3)
    assert dataset.render_utterance(replace(noise, far=1.0)) == dataset.render_utterance(noise)
