"""The learned mark verifier: the committed model, its features, and the training harvest."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector
from services.vision.verifier import CLASSES, MODEL_PATH, N_FEATURES, Verifier, hog, patch_features

Box = tuple[int, int, int, int]


def _card(shape: Shape, size: int = 120, angle: float = 20.0) -> tuple[np.ndarray, Box]:
    """A dark mark on a white card on a mid-grey wall; returns the frame and the mark's box."""
    img = np.full((480, 640), 110, np.uint8)
    cx, cy = 320, 240
    cv2.rectangle(img, (cx - size, cy - size), (cx + size, cy + size), 235, -1)
    s = size // 2
    t = max(3, size // 8)
    if shape is Shape.O:
        cv2.circle(img, (cx, cy), s - t // 2, 30, t, cv2.LINE_AA)
    elif shape is Shape.X:
        for a in (angle + 45, angle - 45):
            dx, dy = s * math.cos(math.radians(a)), s * math.sin(math.radians(a))
            cv2.line(img, (int(cx - dx), int(cy - dy)), (int(cx + dx), int(cy + dy)), 30, t, cv2.LINE_AA)
    else:
        pts = np.array(
            [
                (
                    cx + s * math.cos(math.radians(angle + 90 + 120 * k)),
                    cy + s * math.sin(math.radians(angle + 90 + 120 * k)),
                )
                for k in range(3)
            ],
            np.int32,
        )
        cv2.polylines(img, [pts], True, 30, t, cv2.LINE_AA)
    return img, (cx - s - t, cy - s - t, 2 * (s + t), 2 * (s + t))


def test_the_committed_model_loads_and_is_small() -> None:
    v = Verifier.load()
    assert MODEL_PATH.stat().st_size < 200_000
    p = v.probabilities(np.zeros((3, N_FEATURES), np.float32))
    assert p.shape == (3, len(CLASSES))
    assert np.allclose(p.sum(axis=1), 1.0)


@pytest.mark.parametrize("shape", [Shape.X, Shape.O, Shape.TRIANGLE])
def test_a_clean_mark_is_its_own_class_and_not_another(shape: Shape) -> None:
    v = Verifier.load()
    img, box = _card(shape)
    assert v.accepts(img, box, shape)
    probs = v.probabilities(patch_features(img, box, shape))[0]
    assert int(np.argmax(probs)) == CLASSES.index(shape)


def test_texture_is_not_a_mark() -> None:
    v = Verifier.load()
    yy, xx = np.mgrid[0:480, 0:640]
    img = np.where(((yy // 9) + (xx // 9)) % 2 == 0, 40, 220).astype(np.uint8)
    for shape in (Shape.X, Shape.O, Shape.TRIANGLE):
        assert not v.accepts(img, (280, 200, 80, 80), shape)


def test_the_detector_uses_the_verifier_and_can_do_without() -> None:
    img, _ = _card(Shape.X)
    assert [d.shape for d in MarkDetector().detect(img)] == [Shape.X]
    assert MarkDetector().verifier is not None
    assert MarkDetector(DetectorConfig(verify=False)).verifier is None
    strict = Verifier.load(thresholds=(1.01, 1.01, 1.01))  # nothing is that sure: every candidate is refused
    assert MarkDetector(verifier=strict).detect(img) == []


def test_hog_is_normalised_and_orientation_sensitive() -> None:
    vertical = np.zeros((32, 32), np.uint8)
    vertical[:, 16:] = 255
    h_v = hog(vertical)
    h_h = hog(np.ascontiguousarray(vertical.T))
    assert h_v.shape == (324,)
    assert np.all(h_v >= 0) and np.all(h_v <= 1.0)
    assert not np.allclose(h_v, h_h)


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    v = Verifier.load()
    out = tmp_path / "v.npz"
    Verifier(v.mean, v.scale, v.weights, v.biases, thresholds=(0.2, 0.7, 0.6)).save(out)
    w = Verifier.load(out)
    assert w.thresholds == pytest.approx((0.2, 0.7, 0.6))
    x = np.random.default_rng(0).standard_normal((5, N_FEATURES)).astype(np.float32)
    assert np.allclose(v.probabilities(x), w.probabilities(x), atol=1e-5)


def test_a_model_for_other_features_is_refused(tmp_path: Path) -> None:
    v = Verifier.load()
    bad = Verifier(v.mean[:-1], v.scale[:-1], (v.weights[0][:-1], *v.weights[1:]), v.biases)
    bad.save(tmp_path / "bad.npz")
    with pytest.raises(ValueError, match="features"):
        Verifier.load(tmp_path / "bad.npz")


def test_the_harvest_is_deterministic_and_labelled() -> None:
    from services.vision.training import harvest

    a = harvest(3, 8)
    b = harvest(3, 8)
    assert all(np.array_equal(p, q) for p, q in zip(a, b, strict=True))
    feats, labels, kept = a
    assert feats.shape[1] == N_FEATURES
    assert set(labels.tolist()) <= set(range(len(CLASSES)))
    assert len(labels) == len(kept) > 0


def _filled_triangle(half: int, r: int) -> np.ndarray:
    """A dark filled triangle of radius `r` on a light surface reaching `half` px from it on a darker
    wall: a card when `half` is small, a poster or painted wall when it fills the frame."""
    img = cv2.GaussianBlur(np.random.default_rng(0).integers(40, 90, (480, 640)).astype(np.uint8), (9, 9), 0)
    cv2.rectangle(img, (320 - half, 240 - half), (320 + half, 240 + half), 222, -1)
    a = np.radians(17 + 120 * np.arange(3))
    pts = np.stack([320 + r * np.cos(a), 240 + r * np.sin(a)], axis=1).astype(np.int32)
    cv2.fillPoly(img, [pts], 35, cv2.LINE_AA)
    return img


@pytest.mark.parametrize("r", [45, 70])
def test_a_filled_triangle_is_a_mark_on_a_card_but_not_on_a_wall(r: int) -> None:
    """Only the verifier's context crop tells the two apart (the card tests accept any plain light
    surface); training draws triangles on walls three times as often as the tuning generator."""
    det = MarkDetector()
    assert [d.shape for d in det.detect(_filled_triangle(int(1.4 * r), r))] == [Shape.TRIANGLE]
    assert det.detect(_filled_triangle(300, r)) == []
    # the card tests alone pass both
    assert [d.shape for d in MarkDetector(DetectorConfig(verify=False)).detect(_filled_triangle(300, r))] == [
        Shape.TRIANGLE
    ]
