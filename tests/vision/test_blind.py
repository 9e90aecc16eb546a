"""The blind frame generator: determinism, frame format, labels that match the rendered ink, spread of sizes,
styles, tilts and blur. It never runs the detector: the generator is meant to stay blind to it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.blind import MAX_TILT_DEG, STYLES, BlindGenerator, BlindLabel

SHAPES: list[Shape | None] = [Shape.X, Shape.O, Shape.TRIANGLE, None]


def _run(seed: int, n: int) -> list[tuple[Shape | None, np.ndarray, BlindLabel | None]]:
    gen = BlindGenerator(seed)
    out = []
    for i in range(n):
        shape = SHAPES[i % len(SHAPES)]
        img, label = gen.frame(shape)
        out.append((shape, img, label))
    return out


@pytest.fixture(scope="module")
def hundred() -> list[tuple[Shape | None, np.ndarray, BlindLabel | None]]:
    return _run(11, 100)


def test_same_seed_same_frames_and_different_seeds_differ() -> None:
    a, b, c = _run(3, 6), _run(3, 6), _run(4, 6)
    for (_, ia, la), (_, ib, lb) in zip(a, b, strict=True):
        assert np.array_equal(ia, ib)
        assert la == lb
    assert any(not np.array_equal(ia, ic) for (_, ia, _), (_, ic, _) in zip(a, c, strict=True))


def test_frames_are_bgr_uint8_of_the_requested_size() -> None:
    gen = BlindGenerator(1, width=640, height=480)
    for shape in SHAPES:
        img, _ = gen.frame(shape)
        assert img.shape == (480, 640, 3)
        assert img.dtype == np.uint8
        assert img.std() > 5  # a scene, not a flat fill


def test_smaller_frames_keep_the_mark_inside() -> None:
    gen = BlindGenerator(2, width=320, height=240)
    for shape in (Shape.O, Shape.X, Shape.TRIANGLE):
        img, label = gen.frame(shape)
        assert img.shape == (240, 320, 3)
        assert label is not None
        x, y, w, h = label.box
        assert x >= 0 and y >= 0 and x + w <= 320 and y + h <= 240


def test_each_request_is_honoured(hundred: list[tuple[Shape | None, np.ndarray, BlindLabel | None]]) -> None:
    for shape, _, label in hundred:
        if shape is None:
            assert label is None
        else:
            assert label is not None and label.shape is shape


def test_labels_are_consistent(hundred: list[tuple[Shape | None, np.ndarray, BlindLabel | None]]) -> None:
    labels = [lab for _, _, lab in hundred if lab is not None]
    for lab in labels:
        x, y, w, h = lab.box
        assert x >= 0 and y >= 0 and w > 0 and h > 0
        assert x + w <= 640 and y + h <= 480
        assert lab.size == max(w, h)
        assert 0.0 <= lab.tilt_deg <= MAX_TILT_DEG + 1e-6
        assert lab.blur_px == 0.0 or 2.0 <= lab.blur_px <= 20.0
        assert lab.style in STYLES
        if lab.filled:
            assert lab.shape is Shape.TRIANGLE
        if lab.style == "tape":
            assert lab.shape is not Shape.O and not lab.filled


def test_the_mix_covers_every_style_and_condition(
        hundred: list[tuple[Shape | None, np.ndarray, BlindLabel | None]]) -> None:
    labels = [lab for _, _, lab in hundred if lab is not None]
    assert {lab.style for lab in labels} == set(STYLES)
    assert any(lab.filled for lab in labels) and any(not lab.filled and lab.shape is Shape.TRIANGLE for lab in labels)
    assert any(lab.finger_near for lab in labels) and not all(lab.finger_near for lab in labels)
    assert any(lab.blur_px > 0 for lab in labels) and any(lab.blur_px == 0 for lab in labels)
    tilts = [lab.tilt_deg for lab in labels]
    assert max(tilts) > 30 and min(tilts) < 10


def test_sizes_span_small_to_large(hundred: list[tuple[Shape | None, np.ndarray, BlindLabel | None]]) -> None:
    sizes = np.array([lab.size for _, _, lab in hundred if lab is not None])
    assert sizes.min() >= 20 and sizes.max() <= 480
    assert sizes.min() < 60 and sizes.max() > 200
    assert np.mean((sizes >= 35) & (sizes <= 100)) > 0.3  # many small marks, as a robot sees them at 1-3 m


def test_box_holds_ink_darker_or_more_saturated_than_the_card() -> None:
    gen = BlindGenerator(5)
    gen._clean = True  # no blur, noise, mosaic, glare or JPEG: compare the ink with the paper directly
    for i in range(18):
        img, label = gen.frame(SHAPES[i % 3])
        assert label is not None
        ink = gen._warped_ink > 0.9
        x, y, w, h = label.box
        inside = np.zeros_like(ink)
        inside[y:y + h, x:x + w] = True
        assert ink[inside].mean() > 0.03
        assert not ink[~inside].any()  # the box is the ink's box
        hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV).astype(float)
        paper = inside & ~cv2.dilate(ink.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
        paper &= gen._warped_hand < 0.1
        if paper.sum() < 20:  # the mark fills its box: compare with a ring just outside it
            ring = np.zeros_like(ink)
            ring[max(0, y - 6):y + h + 6, max(0, x - 6):x + w + 6] = True
            paper = ring & ~inside & (gen._warped_hand < 0.1)
        ink_v, ink_s = np.median(hsv[..., 2][ink]), np.median(hsv[..., 1][ink])
        paper_v, paper_s = np.median(hsv[..., 2][paper]), np.median(hsv[..., 1][paper])
        assert ink_v < paper_v - 25 or ink_s > paper_s + 50, (label, ink_v, paper_v, ink_s, paper_s)


def test_plus_signs_change_only_the_signs_drawn() -> None:
    """`plus_signs` (upright "+" signs, X marks turned by 45 degrees under the contract) draws the same scenes
    with the same labels: a disc stands in for each sign otherwise, from the same random draws."""
    plain, signs = BlindGenerator(5), BlindGenerator(5, plus_signs=True)
    differ = 0
    for i in range(40):
        shape = SHAPES[i % len(SHAPES)]
        (a, la), (b, lb) = plain.frame(shape), signs.frame(shape)
        assert la == lb
        differ += not np.array_equal(a, b)
    assert 0 < differ < 40
