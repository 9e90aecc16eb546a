"""Clips weighted in the fit: a training split (`TrainConfig.split_weights`, `train --split-weight`; round voice24) and
the near-command negatives (`TrainConfig.near_weight`, `train --near-weight`; round voice25)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.voice.training import corpus, dataset, folds, train
from services.voice.training.train import TrainConfig
from tests.voice.conftest import TrainCli

N = len(corpus.VOCABULARY)
GO = corpus.VOCABULARY.index("go")


def test_row_weights_names_each_clip_by_its_split() -> None:
    names = np.array(["train", "neural", "engines", "neural"])
    assert train.row_weights(names, TrainConfig()) is None
    cfg = TrainConfig(split_weights=(("neural", 0.5),))
    assert train.row_weights(names, cfg).tolist() == [1.0, 0.5, 1.0, 0.5]
    with pytest.raises(ValueError, match="'foreign' is weighted but no training clip comes from it"):
        train.row_weights(names, TrainConfig(split_weights=(("foreign", 2.0),)))
    with pytest.raises(ValueError, match="must be above 0"):
        train.row_weights(names, TrainConfig(split_weights=(("neural", 0.0),)))


def test_clip_weights_weigh_the_near_command_negatives_only() -> None:
    near = folds.near_words(dataset.Sizes(), 12)[:2]
    texts = np.array([near[0], near[1], "table", near[0], "go"])
    y = np.array([N, N, N, N, GO])
    names = np.array(["train", "neural", "train", "speakers", "neural"])
    assert train.clip_weights(names, texts, y, TrainConfig()) is None
    assert train.clip_weights(names, texts, y, TrainConfig(near_weight=2.0)).tolist() == [2, 2, 1, 2, 1]
    both = TrainConfig(near_weight=2.0, split_weights=(("neural", 0.5),))
    assert train.clip_weights(names, texts, y, both).tolist() == [2, 1, 1, 2, 0.5]
    with pytest.raises(ValueError, match="near weight 0.0: must be above 0"):
        train.clip_weights(names, texts, y, TrainConfig(near_weight=0.0))


@pytest.mark.parametrize("crops", [0, 2])
def test_crop_rows_multiplies_the_class_weights_and_keeps_their_mean(crops: int) -> None:
    x = np.random.default_rng(0).normal(size=(6, 8, 3)).astype(np.float32)
    y = np.array([0, 0, N, N, N, N])
    cfg = TrainConfig(crop_width=4 if crops else 0, crop_starts=(0, 4)[:crops] if crops else ())
    _, _, plain, _, _ = train.crop_rows(x, y, cfg)
    half = np.array([1, 0.5, 1, 1, 0.5, 0.5])
    _, ys, weighted, _, _ = train.crop_rows(x, y, cfg, half)
    assert weighted.mean() == pytest.approx(1.0) and plain.mean() == pytest.approx(1.0)
    ratio = weighted / plain  # per row: the clip's weight, up to the common normalisation
    tiled = np.tile(half, max(crops, 1))
    assert len(ys) == len(tiled) and np.allclose(ratio / ratio[0], tiled)


def _clusters(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every class its own cluster ("train"); then a "neural" voice whose "go"s sit on the "other" cluster."""
    centres = rng.normal(size=(N + 1, 6)) * 4
    x = np.concatenate([centres[c] + rng.normal(size=(60, 6)) for c in range(N + 1)]
                       + [centres[N] + rng.normal(size=(60, 6))])
    y = np.array([c for c in range(N + 1) for _ in range(60)] + [GO] * 60)
    names = np.array(["train"] * ((N + 1) * 60) + ["neural"] * 60)
    return x.reshape(-1, 2, 3).astype(np.float32), y, names


def test_a_lighter_split_pulls_the_head_less() -> None:
    x, y, names = _clusters(np.random.default_rng(2))
    cfg = TrainConfig(hidden=16, ensemble=1, crop_width=0, blas_threads=1)
    others = x[(names == "train") & (y == N)]
    go_on_others = {}
    for w in (1.0, 0.1):
        weighted = replace(cfg, split_weights=(("neural", w),))
        head = train.fit(x, y, weighted, train.row_weights(names, weighted))
        go_on_others[w] = float(head.probabilities(others)[:, GO].mean())
    assert go_on_others[0.1] < go_on_others[1.0] - 0.05


def test_run_folds_fits_each_fold_with_its_rows_weights(monkeypatch: pytest.MonkeyPatch) -> None:
    x, y, names = _clusters(np.random.default_rng(3))
    cfg = TrainConfig(hidden=8, ensemble=1, crop_width=0, word_folds=2, blas_threads=1,
                      split_weights=(("neural", 0.5),))
    words = folds.near_words(cfg.sizes, cfg.seed)[:4]
    texts = np.array(["table"] * len(y), dtype=object)
    other = np.flatnonzero((y == N) & (names == "train"))
    texts[other[:40]] = np.repeat(words, 10)  # 10 "other" clips of each near word
    weight = train.row_weights(names, cfg)
    seen: list[tuple[int, np.ndarray | None]] = []
    real = folds.fit
    monkeypatch.setattr(folds, "fit", lambda xs, ys, c, w=None: (seen.append((len(ys), w)), real(xs, ys, c, w))[1])
    folds.run_folds(x, y, texts.astype(str), (x, y), cfg, progress=False, clip_weight=weight)
    assert len(seen) == 2
    for rows, w in seen:
        assert w is not None and len(w) == rows == len(y) - 20  # each fold leaves its two words' clips out
        assert (w == 0.5).sum() == 60  # and keeps the neural rows' weight


def test_train_split_weight_option(train_cli: TrainCli) -> None:
    assert train_cli("--neural", "150", "--split-weight", "neural=0.5", "--out", "/dev/null").exit_code == 0
    sizes = replace(dataset.Sizes(), neural_positives=150)
    assert train_cli.recipes == [train.shipped_recipe(sizes=sizes, split_weights=(("neural", 0.5),))]
    assert train.shipped_recipe().split_weights == ()
    for bad in ("neural", "neural=", "neural=zero", "neural=-1", "neural=0"):
        refused = train_cli("--neural", "150", "--split-weight", bad, "--out", "/dev/null")
        assert refused.exit_code == 2 and "give SPLIT=W with W a number above 0" in refused.output, bad
    assert train_cli("--near-weight", "2", "--out", "/dev/null").exit_code == 0
    assert train_cli.recipes[-1] == train.shipped_recipe(near_weight=2.0) and train.shipped_recipe().near_weight == 1
    assert train_cli("--near-weight", "0", "--out", "/dev/null").exit_code == 2
    assert train_cli("--alpha", "0.3", "--out", "/dev/null").exit_code == 0
    assert train_cli.recipes[-1] == train.shipped_recipe(alpha=0.3) and train.shipped_recipe().alpha == 0.1
    assert train_cli("--alpha", "0", "--out", "/dev/null").exit_code == 2
    del train_cli.seen[-2:]
    no_split = train_cli("--split-weight", "neural=0.5", "--out", "/dev/null")
    assert no_split.exit_code == 2 and "neural: not a training split of this recipe" in no_split.output
    assert len(train_cli.seen) == 1
