"""The spotter's training corpus: one-edit neighbours of the commands, their train/tune/held-out split,
and temperature scaling. No speech is synthesised here (recipes only)."""

from __future__ import annotations

import numpy as np
import pytest

from services.voice.spotter.head import Head
from services.voice.synth import OOV_HELDOUT
from services.voice.training import corpus, dataset
from services.voice.training.train import fit_temperature

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
    spoken = {r.text for name in ("train", "engines", "neighbours", "tune", "neighbours-tune")
              for r in dataset.recipes(name, sizes, 12)}
    assert not spoken & set().union(*held_groups)
    assert not spoken & set(OOV_HELDOUT)
    assert "glow" not in spoken


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
