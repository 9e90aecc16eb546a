"""The detector's shortcuts that must not change a single detection: each gives the very answer of the
plain computation it replaces (round vision25)."""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from services.vision.detector import _around, _Letters, _line_of_letters, _masked_median, _percentile


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.integers(0, 2**32 - 1), st.integers(1, 60), st.integers(1, 60), st.floats(0.0, 1.0))
def test_masked_median_is_numpys_median(seed: int, h: int, w: int, share: float) -> None:
    """The card's paper level from a histogram equals `np.median` of the masked pixels, for odd and even
    counts, narrow and wide grey ranges."""
    rng = np.random.default_rng(seed)
    lo = int(rng.integers(0, 256))
    g = rng.integers(lo, min(256, lo + int(rng.integers(1, 257))), (h, w), dtype=np.uint8)
    mask = np.where(rng.random((h, w)) < share, 255, 0).astype(np.uint8)
    n = cv2.countNonZero(mask)
    if n == 0:
        mask[int(rng.integers(h)), int(rng.integers(w))] = 255
        n = 1
    assert _masked_median(g, mask, n) == float(np.median(g[mask > 0]))


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 80),
    st.integers(1, 80),
    st.one_of(st.just(90.0), st.just(0.0), st.just(100.0), st.floats(0.0, 100.0)),
)
def test_percentile_is_numpys_bit_for_bit(seed: int, h: int, w: int, q: float) -> None:
    """A letter's paper level from a histogram is `np.percentile`'s, to the last bit, whatever the box's
    size and grey range (`_in_text_line` compares it with other levels)."""
    rng = np.random.default_rng(seed)
    lo = int(rng.integers(0, 256))
    g = rng.integers(lo, min(256, lo + int(rng.integers(1, 257))), (h, w), dtype=np.uint8)
    expected = float(np.percentile(g, q))
    assert _percentile(g, q) == expected
    view = np.zeros((h + 4, w + 4), np.uint8)
    view[2:-2, 2:-2] = g  # a box cut out of a bigger image, as the text-line test reads it
    assert _percentile(view[2:-2, 2:-2], q) == expected


def _letters(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """A grey image, its labels and the components' stats (the candidate is label 1), and the angle of
    the line its neighbours are on: up to 30 letters of about its size on its baseline (horizontal, as
    far as the baseline test reaches and a little beyond), on a line turned by that angle (as far as
    the turned test reaches and beyond) or anywhere within 5 sizes, printed in the candidate's ink or
    lighter, whole or hollow."""
    g = np.full((1000, 1000), 225, np.uint8)
    labels = np.zeros(g.shape, np.uint16)
    h0 = int(rng.integers(14, 60))
    w0 = int(h0 * rng.uniform(0.5, 1.0))
    x0, y0 = 500 - w0 // 2, 500 - h0 // 2
    size = max(w0, h0)
    turn = float(rng.uniform(0, 180))
    t = np.radians(turn)
    boxes = [(x0, y0, w0, h0)]
    for _ in range(int(rng.integers(1, 31))):
        h = int(h0 * rng.uniform(0.65, 1.5))
        w = max(1, int(h0 * rng.uniform(0.08, 1.6)))
        kind = rng.random()
        if kind < 0.45:  # on the baseline, left or right, a gap of up to 2.3 heights (often near 2)
            gap = (rng.uniform(1.6, 2.3) if rng.random() < 0.5 else rng.uniform(-0.2, 2.3)) * h0
            x = int(x0 + w0 + gap) if rng.random() < 0.5 else int(x0 - gap - w)
            y = y0 + h0 - h + int(rng.integers(-2, 3))
        else:
            if kind < 0.8:  # on the turned line, up to 3 sizes along it
                along, across = rng.choice([-1, 1]) * rng.uniform(0.3, 3.0) * size, rng.uniform(-0.2, 0.2) * h0
            else:  # anywhere near
                along, across = rng.uniform(-5, 5) * size, rng.uniform(-5, 5) * size
            cx = 500 + along * np.cos(t) - across * np.sin(t)
            cy = 500 + along * np.sin(t) + across * np.cos(t)
            x, y = int(cx - w / 2), int(cy - h / 2)
        boxes.append((x, y, w, h))
    for k, (x, y, w, h) in reversed(list(enumerate(boxes, start=1))):  # the candidate on top, whole
        ink = 30 if rng.random() < 0.8 else int(rng.integers(60, 200))
        region = (slice(max(0, y), y + h), slice(max(0, x), x + w))
        g[region] = ink
        labels[region] = k
        if rng.random() < 0.5:  # a hollow letter: less than its box is ink
            inner = (slice(max(0, y + h // 4), y + 3 * h // 4), slice(max(0, x + w // 4), x + 3 * w // 4))
            g[inner], labels[inner] = 225, 0
    # the drawing order's labels and their boxes (what is left of each after the later ones)
    stats = np.zeros((len(boxes) + 1, 5), np.int32)
    stats[0] = (0, 0, g.shape[1], g.shape[0], 0)
    for k, (x, y, w, h) in enumerate(boxes, start=1):
        x, y = max(0, x), max(0, y)
        ys, xs = np.nonzero(labels[y : y + h, x : x + w] == k)
        if len(xs):
            stats[k] = (x + xs.min(), y + ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1, len(xs))
    return g, labels, stats, turn


@settings(max_examples=400, deadline=None, derandomize=True)
@given(st.integers(0, 2**32 - 1), st.sampled_from([0.0, 0.7]))
def test_text_line_neighbourhood_changes_no_verdict(seed: int, paper_share: float) -> None:
    """`_around` keeps every component the text-line tests could count, at any angle: the verdict over
    its rows is the verdict over every component of the level; and the levels `_Letters` keeps from one
    line to the next give each line the verdict fresh ones would."""
    rng = np.random.default_rng(seed)
    g, labels, stats, turn = _letters(rng)
    i = 1
    every = np.array([j for j in range(1, len(stats)) if j != i], dtype=np.int64)
    near = _around(stats, i)
    assert set(near.tolist()) <= set(every.tolist())
    assert list(near) == sorted(near)
    angles = [0.0, turn, 90.0]
    measured = _Letters(g, labels, stats, i, paper_share)  # one for every line, as `_in_text_line` has
    for angle in angles:
        assert _line_of_letters(measured, angle, near) == _line_of_letters(
            _Letters(g, labels, stats, i, paper_share), angle, every  # fresh: nothing carried over
        ), angle
