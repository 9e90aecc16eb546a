"""A face is not an O: islands of ink in an O's hole (`hole_islands`, `DetectorConfig.o_islands`, round vision52)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, hole_islands
from tests.vision.test_proposer import _blind_frame, _boxes
from tests.vision.test_star import _card

BOX = (30, 30, 140, 140)  # round `_ring`: radius 64 at the middle of its 12 px stroke, 70 at its outer edge


def _ring(g: np.ndarray) -> None:
    cv2.circle(g, (100, 100), 64, 40, 12)


def test_hole_islands_see_a_face_s_eyes_and_mouth_not_a_fingertip_or_a_speck() -> None:
    """A blank ring's hole holds no island. A face's eyes and mouth are separate blobs inside it, over 1 % of the box.
    A fingertip reaching into the hole comes in across the ring from outside, so it is no island; a speck of noise is
    too small to count; a card with no ink has none."""
    assert hole_islands(_card(_ring), BOX) == 0.0

    def face(g: np.ndarray) -> None:
        _ring(g)
        for dx in (-22, 22):
            cv2.ellipse(g, (100 + dx, 85), (9, 6), 0, 0, 360, 40, -1)
        cv2.ellipse(g, (100, 118), (22, 9), 0, 0, 180, 60, 3)

    assert hole_islands(_card(face), BOX) > DetectorConfig(o_islands=0.01).o_islands

    def fingertip(g: np.ndarray) -> None:
        _ring(g)
        cv2.line(g, (199, 130), (110, 110), 90, 22)  # from past the card's edge, across the ring, into the hole

    assert hole_islands(_card(fingertip), BOX) == 0.0
    # the same grey lying wholly in the hole is an island: the finger was ink, joined to the ring
    assert hole_islands(_card(lambda g: (_ring(g), cv2.line(g, (125, 112), (105, 108), 90, 22))), BOX) > 0.03
    assert hole_islands(_card(lambda g: (_ring(g), cv2.circle(g, (100, 100), 2, 40, -1))), BOX) == 0.0
    assert hole_islands(_card(lambda g: None), BOX) == 0.0


def test_a_face_taken_for_an_o_is_refused_with_o_islands() -> None:
    """Diagnostic blind seed 853, frame 7 (mark-free): a face is reported as an O at 0.97, above the confidence from
    which round vision49's blank-middle test spares an O (one of three faces on seeds 853 and 863, round vision52);
    with `o_islands` 0.01 it is refused. Out-of-range settings are refused, naming them."""
    img, label = _blind_frame(853, 7)
    assert label is None
    assert len(_boxes(DetectorConfig(o_islands=0.0), img, Shape.O)) == 1
    assert not _boxes(DetectorConfig(o_islands=0.01), img, Shape.O)
    for bad in (-0.1, 1.5):
        with pytest.raises(ValueError, match="o_islands"):
            DetectorConfig(o_islands=bad)
