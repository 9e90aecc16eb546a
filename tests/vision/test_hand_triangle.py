"""The second network's word on triangles (`DetectorConfig.hand_triangle`, round vision34): it keeps triangles
drawn by hand that the verifier refused, it is asked only about claimed triangles, and it adds nothing but
triangles."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector, box_overlap, parse_settings
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import INPUT_FORMAT, TRIANGLES_PATH, Verifier, claim, crops

ON = 0.8  # the threshold round vision34 chose on tuning frames, the default since (docs/experiments/rules)


@pytest.fixture(scope="module")
def detectors() -> tuple[MarkDetector, MarkDetector]:
    return MarkDetector(DetectorConfig(hand_triangle=0.0)), MarkDetector(DetectorConfig(hand_triangle=ON))


def _frames(seed: int, count: int, shapes: tuple[Shape | None, ...]) -> list[tuple[np.ndarray, object]]:
    """Tuning-generator frames with every mark drawn by hand, half the triangles filled."""
    gen = SceneGenerator(seed=seed, variation=Variation(hand_drawn=1.0, filled_triangle=0.5))
    out = []
    for i in range(count):
        img, labels = gen.render(gen.scene(shapes[i % len(shapes)]))
        out.append((img, labels[0] if labels else None))
    return out


@pytest.mark.parametrize(("seed", "index"), [(2, 19), (2, 25), (3, 18)])
def test_a_triangle_drawn_by_hand_that_the_verifier_refused_is_kept(
    detectors: tuple[MarkDetector, MarkDetector], seed: int, index: int
) -> None:
    img, label = _frames(seed, index + 1, (Shape.TRIANGLE,))[index]
    off, on = detectors

    def found(det: MarkDetector) -> bool:
        return any(d.shape is Shape.TRIANGLE and box_overlap(d.box, label.box) >= 0.5 for d in det.detect(img))  # type: ignore[attr-defined]

    assert not found(off) and found(on)


def test_the_second_network_is_asked_only_about_claimed_triangles_and_adds_only_triangles(
    detectors: tuple[MarkDetector, MarkDetector], monkeypatch: pytest.MonkeyPatch
) -> None:
    off, on = detectors
    assert on.triangles is not None
    asked: list[np.ndarray] = []

    class Spy:  # the second network, recording what it is asked about
        def __init__(self, second: Verifier) -> None:
            self.second = second

        def probabilities(self, crops: np.ndarray, claims: np.ndarray) -> np.ndarray:
            asked.append(claims)
            return self.second.probabilities(crops, claims)

    monkeypatch.setattr(on, "triangles", Spy(on.triangles))
    added = []
    for img, _ in _frames(5, 60, (Shape.X, Shape.O, Shape.TRIANGLE, None)):
        before = off.detect(img)
        added += [d for d in on.detect(img) if not any(d == b for b in before)]
    assert asked, "60 frames drawn by hand gave the second network nothing to judge"
    assert all((c == claim(Shape.TRIANGLE)).all() for rows in asked for c in rows)
    assert added and all(d.shape is Shape.TRIANGLE for d in added)


def test_on_by_default_off_loads_nothing_and_a_bad_threshold_is_refused() -> None:
    assert DetectorConfig().hand_triangle == ON and MarkDetector().triangles is not None  # since round vision34
    assert MarkDetector(DetectorConfig(hand_triangle=0.0)).triangles is None
    assert MarkDetector(DetectorConfig(hand_triangle=ON, verify=False)).triangles is None  # it needs the verifier
    assert parse_settings(f"hand_triangle={ON}").hand_triangle == ON
    with pytest.raises(ValueError, match=r"hand_triangle: 1.5: a probability"):
        parse_settings("hand_triangle=1.5")


def test_the_committed_second_network_takes_the_verifiers_inputs() -> None:
    second = Verifier.load(TRIANGLES_PATH)
    meta = second.session.get_modelmeta().custom_metadata_map
    assert meta["input_format"] == INPUT_FORMAT
    assert TRIANGLES_PATH.stat().st_size < 400_000  # small, as the README says


def test_loose_candidates_are_asked_only_when_the_verifier_half_believes_a_triangle(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """`hand_triangle_loose` (round vision35): which rows of a frame's verifier call reach the second network."""
    det = MarkDetector(DetectorConfig(hand_triangle=ON, hand_triangle_loose=0.9, hand_triangle_floor=0.3))
    assert det.triangles is not None
    asked: list[int] = []
    second = det.triangles

    class Spy:  # the real second network, recording how many rows it is asked about
        def probabilities(self, crops: np.ndarray, claims: np.ndarray) -> np.ndarray:
            asked.append(len(crops))
            return second.probabilities(crops, claims)

    monkeypatch.setattr(det, "triangles", Spy())
    # the verifier's rows (X, O, TRIANGLE, none) for: a loose one it half-believes a triangle (asked), a loose one
    # under the floor, a loose one it names itself, a claimed triangle it refuses (asked), a card-test rescue
    # and a claimed X it refuses (neither asked)
    pending = [
        SimpleNamespace(shape=None, rescue=False),
        SimpleNamespace(shape=None, rescue=False),
        SimpleNamespace(shape=None, rescue=False),
        SimpleNamespace(shape=Shape.TRIANGLE, rescue=False),
        SimpleNamespace(shape=Shape.TRIANGLE, rescue=True),
        SimpleNamespace(shape=Shape.X, rescue=False),
    ]
    probs = np.array(
        [[0, 0, 0.5, 0.5], [0, 0, 0.2, 0.8], [0, 0, 0.95, 0.05], [0, 0, 0.5, 0.5], [0, 0, 0.5, 0.5], [0.1, 0, 0, 0.9]],
        dtype=np.float32,
    )
    img, label = _frames(2, 20, (Shape.TRIANGLE,))[19]
    assert label is not None
    patches = np.stack([crops(img[:, :, 1], label.box)] * len(pending))  # type: ignore[attr-defined]
    claims = np.stack([claim(p.shape) for p in pending])
    out = det._second_triangles(pending, patches, claims, probs)  # type: ignore[arg-type]
    assert asked == [2]
    assert all(out[j] is None for j in (1, 2, 4, 5))
    off = MarkDetector(DetectorConfig(hand_triangle=ON, hand_triangle_loose=0.0))
    monkeypatch.setattr(off, "triangles", Spy())
    asked.clear()
    off._second_triangles(pending, patches, claims, probs)  # type: ignore[arg-type]
    assert asked == [1]  # off: the claimed triangle only, as in round vision34
    with pytest.raises(ValueError, match=r"hand_triangle_floor: -0.1: a probability"):
        parse_settings("hand_triangle_floor=-0.1")


@pytest.mark.parametrize(("seed", "index"), [(2, 16), (2, 34)])
def test_a_loose_triangle_drawn_by_hand_is_named_by_the_second_network(seed: int, index: int) -> None:
    """Round vision35: triangles drawn by hand that the shape tests read nothing in and the verifier does not name
    are found with `hand_triangle_loose` and not without."""
    img, label = _frames(seed, index + 1, (Shape.TRIANGLE,))[index]
    assert label is not None

    def found(config: DetectorConfig) -> bool:
        dets = MarkDetector(config).detect(img)
        return any(d.shape is Shape.TRIANGLE and box_overlap(d.box, label.box) >= 0.5 for d in dets)  # type: ignore[attr-defined]

    assert not found(DetectorConfig(hand_triangle_loose=0.0)) and found(DetectorConfig(hand_triangle_loose=0.8))
