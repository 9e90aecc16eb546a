"""The second network's word on triangles (`DetectorConfig.hand_triangle`, round vision34): it keeps triangles
drawn by hand that the verifier refused, it is asked only about claimed triangles, and it adds nothing but
triangles."""

from __future__ import annotations

import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector, box_overlap, parse_settings
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import INPUT_FORMAT, TRIANGLES_PATH, Verifier, claim

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
