"""Word folds: where the knots must sit for near-command words the head never heard.

`train` places each command's knots on the tune split, whose non-command words the head was fitted on in other
voices. The held-out words are other words, and round 13 showed the difference: its head walked on "co" and
"gao", one-edit neighbours of "go" that no tune clip resembled. This step measures that gap on training data:

1. The near-command negatives the head is fitted on (`near_words`: the hand-picked neighbours, the train
   one-edit neighbours and the two-edit words) are cut into `cfg.word_folds` folds by word.
2. For each fold the recipe is fitted without the fold's words (every voice of them), its temperature and
   knots are placed on the tune splits as `train` does, and it scores the fold's own clips: words it never
   heard, in voices it did.
3. From each fold (`FoldResult`): the "go" sure margin (log-odds above the tune split's worst non-"go") that
   none of the fold's words reached, and per command the shift (log-odds) of its `accept` knot that keeps the
   fold's words published as that command within `cfg.fold_budgets`.

`apply` moves the final head's knots by what the folds found: "go"'s sure knot to the largest margin any fold
needed plus `cfg.fold_sure_extra`, each accept knot by the largest shift any fold needed (the recipe's knots
are kept where the folds need less), except the accept knots of `cfg.fold_accept_exempt`. Nothing here looks at held-out data.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from services.runtime import get_logger
from services.voice.spotter.head import Head
from services.voice.training import corpus, dataset
from services.voice.training.train import TrainConfig, calibrate, fit, fit_temperature, logit, sigmoid

FOLD_SEED = 0


def near_words(sizes: dataset.Sizes, seed: int) -> list[str]:
    """The training negatives that are near a command, sorted."""
    words = {w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws}
    words |= set(dataset.neighbours(sizes, seed)["train"]) | set(dataset.two_edit(sizes))
    return sorted(words)


def word_folds(words: Sequence[str], k: int, seed: int = FOLD_SEED) -> list[list[str]]:
    """`words` shuffled with `seed` and dealt into `k` folds (every word in exactly one)."""
    shuffled = list(words)
    random.Random(seed).shuffle(shuffled)
    return [shuffled[i::k] for i in range(k)]


def accept_shift(p: np.ndarray, best: np.ndarray, c: int, accept: float, budget: float) -> float:
    """Log-odds to add to command c's `accept` so that at most `budget` of these clips (none of them c) would be
    published as c (argmax c and probability >= accept); 0 if the knot already holds them."""
    ranked = np.sort(p[best == c, c])[::-1]
    k = int(np.floor(budget * len(p)))
    if ranked.size <= k or ranked[k] < accept:
        return 0.0
    return logit(float(ranked[k]) + 1e-4) - logit(accept)


@dataclass(frozen=True)
class FoldResult:
    """What one fold's head did on its own unseen words."""

    clips: int
    accepted: int
    """Clips published as some command by the fold's head (its own tune knots)."""
    go_margin: float
    """Log-odds between the tune split's worst non-"go" and the fold's highest "go" probability."""
    shifts: dict[str, float]
    """Per command, the accept shift (log-odds) the fold's words need (`accept_shift`)."""


def score_fold(head: Head, worst_go: float, x: np.ndarray, budgets: dict[str, float],
               default_budget: float) -> FoldResult:
    """`head` (fitted and calibrated without these words) on the fold's clips `x`."""
    p = head.probabilities(x)
    best = p.argmax(axis=1)
    n = len(head.vocabulary)
    accepted = sum(int(np.sum((best == c) & (p[:, c] >= head.accept[c]))) for c in range(n))
    go = head.vocabulary.index("go")
    shifts = {w: accept_shift(p, best, c, float(head.accept[c]), budgets.get(w, default_budget))
              for c, w in enumerate(head.vocabulary)}
    return FoldResult(len(x), accepted, logit(float(p[:, go].max())) - logit(worst_go), shifts)


def run_folds(x: np.ndarray, y: np.ndarray, texts: np.ndarray, tune: tuple[np.ndarray, np.ndarray],
              cfg: TrainConfig, progress: bool = True, scored: np.ndarray | None = None,
              clip_weight: np.ndarray | None = None) -> list[FoldResult]:
    """Fit, calibrate and score one head per fold (`cfg.word_folds` of them) on the training rows, each clip
    weighted by `clip_weight` as the final head's (`train.clip_weights`). A fold's words are left out of its fit
    in every row, and scored only in the rows `scored` marks (default: all; `TrainConfig.fold_unscored`)."""
    results = []
    other = len(corpus.VOCABULARY)
    for k, words in enumerate(word_folds(near_words(cfg.sizes, cfg.seed), cfg.word_folds)):
        out = np.isin(texts, words) & (y == other)
        head = fit(x[~out], y[~out], cfg, None if clip_weight is None else clip_weight[~out])
        fit_temperature(head, *tune)
        chosen = calibrate(head, *tune, cfg)
        worst_go = float(chosen["go"]["worst_other"])  # type: ignore[index]
        fold = out if scored is None else out & scored
        result = score_fold(head, worst_go, x[fold], dict(cfg.fold_budgets), cfg.default_fold_budget)
        if progress:
            get_logger("voice.train").info("word fold", fold=k, words=len(words), clips=result.clips,
                                           accepted=result.accepted, go_margin=round(result.go_margin, 2))
        results.append(result)
    return results


def apply(head: Head, results: Sequence[FoldResult], worst: dict[str, float], cfg: TrainConfig) -> dict[str, object]:
    """Move `head`'s knots (already calibrated on tune; `worst` the tune split's worst non-command per command)
    by what the folds found; returns the margins and shifts used."""
    go = head.vocabulary.index("go")
    recipe_margin = dict(cfg.sure_margin).get("go", cfg.default_sure_margin)
    margin = max(recipe_margin, max(r.go_margin for r in results) + cfg.fold_sure_extra)
    needed = {w: max(r.shifts[w] for r in results) for w in head.vocabulary}
    shifts = {w: 0.0 if w in cfg.fold_accept_exempt else s for w, s in needed.items()}
    for c, w in enumerate(head.vocabulary):
        head.accept[c] = min(sigmoid(logit(float(head.accept[c])) + shifts[w]), 0.9999)
    sure_go = sigmoid(logit(worst["go"]) + margin)
    head.sure[go] = min(max(float(head.sure[go]), sure_go, float(head.accept[go]) + 0.01), 0.99999)
    for c in range(len(head.vocabulary)):
        head.sure[c] = max(float(head.sure[c]), min(float(head.accept[c]) + 0.01, 0.99999))
    report: dict[str, object] = {"go_margin": round(margin, 3), "accept_shifts": {w: round(s, 3) for w, s in shifts.items()}}
    if cfg.fold_accept_exempt:
        report["exempt_shifts_not_applied"] = {w: round(needed[w], 3) for w in cfg.fold_accept_exempt if w in needed}
    report["folds"] = [{"clips": r.clips, "accepted": r.accepted, "go_margin": round(r.go_margin, 3)} for r in results]
    return report
