"""Word-fold calibration (`training/folds.py`): which words are folded, and how the knots move."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from services.voice.spotter.head import Head
from services.voice.training import corpus, dataset, folds
from services.voice.training.train import TrainConfig
from tests.voice.conftest import TrainCli

N = len(corpus.VOCABULARY)
GO = corpus.VOCABULARY.index("go")


def test_near_words_are_the_training_neighbours_and_never_a_command() -> None:
    words = folds.near_words(dataset.Sizes(), 12)
    assert set(corpus.NEIGHBOURS_TRAIN["go"]) <= set(words)
    assert not set(words) & set(corpus.VOCABULARY)
    assert words == sorted(set(words))
    # none of the tune or held-out one-edit neighbours: the folds are made of training words only
    split = dataset.neighbours(dataset.Sizes(), 12)
    assert not set(words) & (set(split["tune"]) | set(split["heldout"]))


def test_word_folds_deal_every_word_once_and_reproducibly() -> None:
    words = [f"w{i}" for i in range(23)]
    dealt = folds.word_folds(words, 5)
    assert len(dealt) == 5 and sorted(w for f in dealt for w in f) == sorted(words)
    assert dealt == folds.word_folds(words, 5)
    assert dealt != folds.word_folds(words, 5, seed=1)


def _probs(top: np.ndarray, c: int) -> tuple[np.ndarray, np.ndarray]:
    """Clips whose best class is c with probability `top`, the rest on "other"."""
    p = np.zeros((len(top), N + 1))
    p[:, c] = top
    p[:, N] = 1 - top
    return p, p.argmax(axis=1)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.55, 0.999), min_size=1, max_size=40), st.integers(0, 60),
       st.floats(0.5, 0.9), st.sampled_from([0.003, 0.01, 0.03]))
def test_the_shifted_accept_knot_publishes_at_most_the_budget(tops: list[float], rest: int, accept: float,
                                                                budget: float) -> None:
    top = np.array(tops + [0.1] * rest)
    p, best = _probs(top, GO)
    shift = folds.accept_shift(p, best, GO, accept, budget)
    assert shift >= 0
    moved = 1 / (1 + np.exp(-(np.log(accept / (1 - accept)) + shift)))
    published = int(np.sum((best == GO) & (p[:, GO] >= moved)))
    assert published <= int(np.floor(budget * len(p)))
    # and it moves no further than it must: one clip more would be published just below it
    if shift > 0:
        assert np.sum((best == GO) & (p[:, GO] >= moved - 2e-4)) > published


def test_a_knot_that_already_holds_the_fold_does_not_move() -> None:
    p, best = _probs(np.array([0.6, 0.7, 0.1, 0.1]), GO)
    assert folds.accept_shift(p, best, GO, 0.8, 0.01) == 0.0


def _head() -> Head:
    dim = 4
    return Head(corpus.VOCABULARY, np.zeros(dim, np.float32), np.ones(dim, np.float32),
                [np.zeros((dim, 1), np.float32), np.zeros((1, N + 1), np.float32)],
                [np.zeros(1, np.float32), np.zeros(N + 1, np.float32)], np.full(N, 0.6), np.full(N, 0.9))


def _result(go_margin: float, shift: float = 0.0) -> folds.FoldResult:
    return folds.FoldResult(100, 3, go_margin, {w: (shift if w == "stop" else 0.0) for w in corpus.VOCABULARY})


def test_apply_puts_go_sure_above_the_worst_fold_and_shifts_accept_knots() -> None:
    head = _head()
    worst = {w: 0.95 for w in corpus.VOCABULARY}
    cfg = TrainConfig(fold_sure_extra=1.0)
    report = folds.apply(head, [_result(1.0), _result(3.2, shift=2.0), _result(0.5)], worst, cfg)
    logit = lambda q: np.log(q / (1 - q))  # noqa: E731
    assert report["go_margin"] == pytest.approx(4.2)
    assert logit(head.sure[GO]) == pytest.approx(logit(0.95) + 4.2, abs=1e-6)
    stop = corpus.VOCABULARY.index("stop")
    assert logit(head.accept[stop]) == pytest.approx(logit(0.6) + 2.0, abs=1e-6)
    assert head.accept[GO] == pytest.approx(0.6)
    assert (head.sure > head.accept).all()  # the stop knots stay in order after its accept moved past 0.9


def test_an_exempt_accept_knot_stays_where_tune_put_it_and_its_sure_knot_still_moves() -> None:
    """Round voice20's candidate: "go" exempt from the folds' accept shift; every other command still shifted."""
    worst = {w: 0.95 for w in corpus.VOCABULARY}
    shifted = [folds.FoldResult(100, 3, 3.2, {w: 1.5 for w in corpus.VOCABULARY})]
    plain, exempt = _head(), _head()
    folds.apply(plain, shifted, worst, TrainConfig())
    report = folds.apply(exempt, shifted, worst, TrainConfig(fold_accept_exempt=("go",)))
    assert exempt.accept[GO] == pytest.approx(0.6) and plain.accept[GO] > 0.8
    others = [c for c, w in enumerate(corpus.VOCABULARY) if w != "go"]
    assert np.array_equal(exempt.accept[others], plain.accept[others]) and (plain.accept[others] > 0.8).all()
    assert np.array_equal(exempt.sure, plain.sure)  # "go" walks unasked exactly as before
    assert report["accept_shifts"]["go"] == 0.0 and report["exempt_shifts_not_applied"] == {"go": 1.5}


def test_apply_never_lowers_the_recipes_go_margin() -> None:
    head = _head()
    worst = {w: 0.5 for w in corpus.VOCABULARY}
    report = folds.apply(head, [_result(-3.0)], worst, TrainConfig())
    assert report["go_margin"] == pytest.approx(2.5)  # the recipe's own margin for "go"
    assert head.sure[GO] == pytest.approx(1 / (1 + np.exp(-2.5)))


def _near_go(rng: np.random.Generator, words: list[str],
             groups: list[tuple[int, float, float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Synthetic features (x, y, texts): 60 clips of every command and of "table", each class its own cluster; then,
    per group (clips, offset, spread), `clips` clips of every word labelled "other" near "go": moved off it in a
    direction of the word's own by `offset`, scattered by `spread`."""
    centres = rng.normal(size=(N + 1, 6)) * 3
    rows, labels, texts = [], [], []
    for c in range(N + 1):
        rows.append(centres[c] + rng.normal(size=(60, 6)))
        labels += [c] * 60
        texts += [corpus.VOCABULARY[c] if c < N else "table"] * 60
    for clips, offset, spread in groups:
        for w in words:
            rows.append(centres[GO] + rng.normal(size=6) * offset + rng.normal(size=(clips, 6)) * spread)
            labels += [N] * clips
            texts += [w] * clips
    return np.concatenate(rows).reshape(-1, 2, 3).astype(np.float32), np.array(labels), np.array(texts)


def test_run_folds_scores_each_fold_on_words_its_head_never_heard() -> None:
    """Synthetic features: every command its own cluster; each near word its own cluster close to "go", so a
    head fitted without a word takes much of it for "go"."""
    rng = np.random.default_rng(0)
    cfg = TrainConfig(hidden=16, ensemble=1, crop_width=0, word_folds=5, blas_threads=1)
    words = folds.near_words(cfg.sizes, cfg.seed)[:40]
    x, y, texts = _near_go(rng, words, [(10, 1.5, 0.5)])  # 10 clips each, near "go" in a direction of their own
    tune_idx = rng.choice((N + 1) * 60, 300, replace=False)  # no near word: the tune split has other words
    results = folds.run_folds(x, y, texts, (x[tune_idx], y[tune_idx]), cfg, progress=False)
    assert len(results) == 5
    assert sum(r.clips for r in results) == 10 * len(words)  # only the near words, each in one fold
    assert all(r.clips % 10 == 0 for r in results)  # a word's clips are never split between folds
    assert all(set(r.shifts) == set(corpus.VOCABULARY) for r in results)
    # the folds see what the tune split cannot: a head that heard these words (as "other") publishes fewer of them
    from services.voice.training import train

    seen = train.fit(x, y, cfg)
    train.fit_temperature(seen, x[tune_idx], y[tune_idx])
    train.calibrate(seen, x[tune_idx], y[tune_idx], cfg)
    near = x[-10 * len(words):]
    p = seen.probabilities(near)
    best = p.argmax(axis=1)
    published_seen = int(sum(np.sum((best == c) & (p[:, c] >= seen.accept[c])) for c in range(N)))
    assert sum(r.accepted for r in results) > published_seen
    assert max(r.shifts["go"] for r in results) > 0 and max(r.go_margin for r in results) > 0


def test_train_fold_accept_exempt_option_sets_only_that(train_cli: TrainCli) -> None:
    from dataclasses import replace

    from services.voice.training import train

    assert train_cli("--fold-accept-exempt", "go", "--out", "/dev/null").exit_code == 0
    assert train_cli("--fold-accept-exempt", "go", "--fold-accept-exempt", "no", "--out", "/dev/null").exit_code == 0
    refused = train_cli("--fold-accept-exempt", "jump", "--out", "/dev/null")
    assert refused.exit_code == 2 and "jump: not a command" in refused.output
    assert train_cli.recipes == [replace(train.shipped_recipe(), fold_accept_exempt=("go",)),
                    replace(train.shipped_recipe(), fold_accept_exempt=("go", "no"))]
    assert train.shipped_recipe().fold_accept_exempt == ()


def test_run_folds_leaves_unscored_rows_out_of_the_score_and_the_fit() -> None:
    """Rows `scored` does not mark (round voice23: the `neural` split's clips) of a fold's words are neither scored
    by the fold nor heard by its head: here they sit on "go" itself, and scored they would raise the fold's "go"
    margin; unscored, a fold scores only its words' other clips (its head is the same either way)."""
    rng = np.random.default_rng(1)
    cfg = TrainConfig(hidden=16, ensemble=1, crop_width=0, word_folds=3, blas_threads=1)
    words = folds.near_words(cfg.sizes, cfg.seed)[:12]
    # 10 clips of each word in the scored voices, near "go" in a direction of their own; then 5 in a voice the folds
    # do not score, said just like "go"
    x, y, texts = _near_go(rng, words, [(10, 4.0, 0.5), (5, 0.0, 0.3)])
    scored = np.ones(len(y), bool)
    scored[-5 * len(words):] = False
    tune_idx = rng.choice((N + 1) * 60, 300, replace=False)
    tune = (x[tune_idx], y[tune_idx])
    every = folds.run_folds(x, y, texts, tune, cfg, progress=False)
    some = folds.run_folds(x, y, texts, tune, cfg, progress=False, scored=scored)
    assert sum(r.clips for r in every) == 15 * len(words) and sum(r.clips for r in some) == 10 * len(words)
    assert max(r.go_margin for r in some) < max(r.go_margin for r in every)
    assert sum(r.accepted for r in some) < sum(r.accepted for r in every)


def test_train_fold_unscored_option(train_cli: TrainCli) -> None:
    from dataclasses import replace

    from services.voice.training import dataset, train

    assert train_cli("--neural", "150", "--fold-unscored", "neural", "--out", "/dev/null").exit_code == 0
    sizes = replace(dataset.Sizes(), neural_positives=150)
    assert train_cli.recipes == [train.shipped_recipe(sizes=sizes, fold_unscored=("neural",))]
    assert train.shipped_recipe().fold_unscored == ()
    no_split = train_cli("--fold-unscored", "neural", "--out", "/dev/null")
    assert no_split.exit_code == 2 and "neural: not a training split of this recipe" in no_split.output
    no_folds = train_cli("--neural", "150", "--fold-unscored", "neural", "--word-folds", "0", "--out", "/dev/null")
    assert no_folds.exit_code == 2 and "give --word-folds N" in no_folds.output
    assert len(train_cli.seen) == 1
