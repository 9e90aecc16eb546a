"""`filled.py` and `DetectorConfig.filled_paper_round` (round vision61): a filled triangle with plain paper all round
it is a mark however far the paper runs (a sheet much wider than the triangle, a card that runs out of the frame, a
white card before a white wall), while a dark wedge that a card's edge cuts from something darker is not."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from bench import vision_bench, vision_cards
from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector
from services.vision.filled import paper_round, solid_share
from services.vision.training import iou

ON = DetectorConfig(filled_paper_round=0.9)


def _triangle(img: np.ndarray, centre: tuple[float, float], r: float, ink: int, thickness: int = -1) -> np.ndarray:
    pts = np.array([[centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)] for a in (-np.pi / 2, np.pi / 6, 5 * np.pi / 6)])
    pts = pts.round().astype(np.int32)
    if thickness < 0:
        cv2.fillPoly(img, [pts], ink, cv2.LINE_AA)
    else:
        cv2.polylines(img, [pts], True, ink, thickness, cv2.LINE_AA)
    return pts


def _outline_in_box(pts: np.ndarray) -> tuple[tuple[int, int, int, int], np.ndarray]:
    x, y, w, h = cv2.boundingRect(pts)
    return (x, y, w, h), (pts - np.array([x, y])).reshape(-1, 1, 2).astype(np.int32)


@pytest.mark.parametrize(("kind", "border"), [("grey", 3.0), ("dark", 1.5), ("texture", 3.0), ("white", 0.3)])
def test_a_filled_triangle_on_plain_paper_is_found_however_far_the_paper_runs(kind: str, border: float) -> None:
    rng = np.random.default_rng(5)
    img, box = vision_cards.card_frame(kind, Shape.TRIANGLE, True, 60, border, 25.0, rng)
    assert not any(d.shape is Shape.TRIANGLE for d in MarkDetector().detect(img))  # the default: a painted wall
    found = MarkDetector(ON).detect(img)
    assert [d.shape for d in found] == [Shape.TRIANGLE] and iou(found[0].box, box) >= 0.5


def test_a_dark_wedge_beside_a_card_is_not_a_mark(base_verifier: str) -> None:
    # diagnostic blind seed 853 (looked at, stop 106), frame 185: below an O's card, a dark wedge that a card's edge
    # cuts from the board behind, paper along one side only - a false TRIANGLE with almost any ring of paper asked,
    # none with 0.9 of it; the O is found either way (about 20 s to draw). The committed verifier's base (the model
    # before round vision68b) names the wedge a triangle at 0.56; the committed model no longer does (at any ring)
    frame_of = vision_bench._generator("blind", 853)
    for i in range(186):
        img, label, _ = frame_of(vision_bench.CLASSES[i % 4])
    assert label is not None and label[0] is Shape.O
    loose = MarkDetector(DetectorConfig(filled_paper_round=0.01, verifier_model=base_verifier)).detect(img)
    assert any(d.shape is Shape.TRIANGLE and iou(d.box, (420, 354, 53, 23)) >= 0.5 for d in loose)
    for config in (DetectorConfig(filled_paper_round=0.9, verifier_model=base_verifier), ON):
        found = MarkDetector(config).detect(img)
        assert [d.shape for d in found] == [Shape.O] and iou(found[0].box, label[1]) >= 0.5


def test_paper_round_is_the_share_of_paper_in_the_ring() -> None:
    g = np.full((200, 200), 230, np.uint8)
    pts = _triangle(g, (100, 100), 30, 20)
    box, outline = _outline_in_box(pts)
    assert paper_round(g, box, outline, 20, 230) == 1.0
    g[:, 120:] = 60  # something dark beside it, in the ring on one side
    assert 0.3 < paper_round(g, box, outline, 20, 230) < 0.9
    edge = np.full((200, 200), 230, np.uint8)
    pts = _triangle(edge, (100, 22), 30, 20)  # the ring would leave the image: what lies there is unknown
    box, outline = _outline_in_box(pts)
    assert paper_round(edge, box, outline, 20, 230) == 0.0


def test_solid_share_tells_a_filled_triangle_from_an_outline() -> None:
    filled = np.full((200, 200), 230, np.uint8)
    box, outline = _outline_in_box(_triangle(filled, (100, 100), 50, 20))
    assert solid_share(filled, box, outline, 20, 230) > 0.95
    drawn = np.full((200, 200), 230, np.uint8)
    box, outline = _outline_in_box(_triangle(drawn, (100, 100), 50, 20, thickness=8))
    assert solid_share(drawn, box, outline, 20, 230) < 0.8


@pytest.mark.parametrize("value", [-0.1, 1.5])
def test_filled_paper_round_out_of_range_is_refused(value: float) -> None:
    with pytest.raises(ValueError, match="filled_paper_round"):
        DetectorConfig(filled_paper_round=value)
