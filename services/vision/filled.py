"""A filled triangle with paper all round it (round vision61, `DetectorConfig.filled_paper_round`).

The verifier judges a filled triangle's context from a crop of four times the mark: where a card's edge falls inside
that crop it names a triangle, and where only light paper does it refuses one, having been taught that a filled
triangle on a light surface that runs on is painted on a wall. A person who holds up a sheet much wider than the
triangle on it, or a card that runs out of the frame, shows it just that: stop 106's look on two spent blind seeds
(`docs/experiments/scripts/vision60_sheet_look.py`) found a whole sheet within 4 times the triangle's size round 2
of 160 missed filled triangles (3 anywhere in view). A wide card and a wall cannot be told apart there, and a
triangle is a danger mark: a false one costs a needless stop, a missed one a walk into danger. So this stage keeps a
filled triangle that the networks refused where plain paper lies all round it, however far that paper runs. A dark
wedge between a card's edge and something else has paper on one or two sides only. Round vision61 judged it and it
did not land (the vision README): letters, warning signs, play buttons, arrow heads and some wedges have paper round
them too, and the option is off by default.
"""

from __future__ import annotations

import cv2
import numpy as np

Box = tuple[int, int, int, int]

FILLED_SHARE = 0.8
"""a shape is filled when this share of its outline's inside is darker than half-way from the ink to the paper (an
outline triangle's inside is mostly paper; blur and JPEG lighten a filled one's rim)"""
LOOSE_TRIANGLE_FILL = 0.8
"""a loose candidate (no shape claimed) must fill this share of its enclosing triangle: the shape tests' bar (0.85)
refuses many a filled triangle whose sides the local threshold bows inwards; a square fills about half, a disc 0.6"""
RING = (0.06, 0.3)
"""the ring looked at, from and to this share of the mark's size out from its outline (the card tests' surround)"""
TOLERANCE = 0.25
"""paper is at least the box's paper grey less this share of the ink contrast (and at least 10 grey levels)"""


def ink_and_paper(g: np.ndarray, box: Box) -> tuple[float, float]:
    """The ink's and the paper's grey in `box`: its 5th and 90th percentiles (a triangle covers about half its box)."""
    x, y, w, h = box
    ink, paper = np.percentile(g[y : y + h, x : x + w], (5, 90))
    return float(ink), float(paper)


def solid_share(g: np.ndarray, box: Box, outline: np.ndarray, ink: float, paper: float) -> float:
    """The share of the region inside `outline` (a contour in `box`'s pixels) darker than half-way from `ink` to
    `paper`: about 1 for a filled shape (also one the local threshold hollowed), far less for most outlines."""
    x, y, w, h = box
    inside = np.zeros((h, w), np.uint8)
    cv2.drawContours(inside, [outline], -1, 255, cv2.FILLED)
    n = cv2.countNonZero(inside)
    if n == 0:
        return 0.0
    dark = cv2.inRange(g[y : y + h, x : x + w], 0, (ink + paper) / 2)
    return cv2.countNonZero(cv2.bitwise_and(inside, dark)) / n


def paper_round(g: np.ndarray, box: Box, outline: np.ndarray, ink: float, paper: float) -> float:
    """The share of a ring round the mark (`RING`, out from `outline`, a contour in `box`'s pixels) that is paper; 0
    where the ring would leave the image (what lies beyond is unknown)."""
    x, y, w, h = box
    side = max(w, h)
    r_in, r_out = max(2, round(RING[0] * side)), max(4, round(RING[1] * side))
    x0, y0, x1, y1 = x - r_out - 1, y - r_out - 1, x + w + r_out + 1, y + h + r_out + 1
    if x0 < 0 or y0 < 0 or x1 > g.shape[1] or y1 > g.shape[0]:
        return 0.0
    mark = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.drawContours(mark, [outline + np.array([[[x - x0, y - y0]]], np.int32)], -1, 255, cv2.FILLED)
    inner = cv2.dilate(mark, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r_in + 1, 2 * r_in + 1)))
    outer = cv2.dilate(mark, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r_out + 1, 2 * r_out + 1)))
    ring = cv2.subtract(outer, inner)
    n = cv2.countNonZero(ring)
    light = cv2.inRange(g[y0:y1, x0:x1], max(0.0, paper - max(10.0, TOLERANCE * (paper - ink))), 255)
    return cv2.countNonZero(cv2.bitwise_and(ring, light)) / n if n else 0.0
