"""Whether a mark lies on a whole card or sheet that ends inside the frame (round vision60).

A filled triangle is a mark on a card and clutter on a wall (the vision README, "What counts as a mark"). The
verifier judges that from a context crop of four times the mark, so a small filled triangle on a large sheet, whose
edges lie outside that crop, looks to it like one painted on a wall and is refused. `whole_sheet` looks further out:
the paper round the mark is followed, up to `reach` times the mark's size beyond its box, and the mark lies on a sheet
if that paper ends on every side before the frame does, as a quadrilateral (four or five corners: a finger or the
blur may cut one) that holds the mark well inside it. A wall, or a surface of the paper's grey behind the card, runs
on past the reach or out of the frame, and the answer is no. The method is stop 75's look
(`docs/experiments/scripts/stop75_card_outline.py`, tuning frames only), made a detector stage.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

Box = tuple[int, int, int, int]

MIN_CONTRAST = 35.0
"""paper minus ink (the box's 90th and 5th grey percentiles) below this: too faint to follow the paper"""
TOLERANCE = 0.25
"""the paper is the grey within this share of the ink contrast of the box's paper (at least `MIN_TOLERANCE`)"""
MIN_TOLERANCE = 10.0
EDGES = (20, 50)
"""Canny's thresholds: the card's edge parts its paper from a background of about its grey"""
MIN_SOLIDITY = 0.8
"""the sheet (the mark included) fills at least this share of its convex hull: a card, not a spill of light paint"""
CORNERS = (4, 5)
"""the hull's corners at 5 % of its perimeter: a quadrilateral, or one with a corner cut (a finger, blur)"""
FILLED_SHARE = 0.8
"""a triangle is filled when this share of its outline's inside is darker than half-way to the paper (an outline's
inside is mostly paper; blur and JPEG lighten a filled one's rim)"""
SHEET_TRIANGLE_FILL = 0.8
"""a loose candidate (no shape claimed) must fill this share of its enclosing triangle: the shape tests' bar (0.85)
refuses many a filled triangle whose sides the local threshold bows inwards; a square fills about half, a disc 0.6"""
WIDER = 3.0
"""the sheet's hull covers at least WIDER^2 x the square of the mark's size: the rule is for sheets wider than the
verifier's context crop shows; a triangle cut from a dark shape by a card's corner lies on no such sheet"""
PLAIN = 0.05
"""at most this share of the sheet's hull is neither its paper nor the mark: a sheet with one mark on it, not a
poster, a page of print or a light wall with words and pictures on it"""
INSIDE = 0.25
"""every corner of the mark's box lies at least this share of its size inside the hull: on the sheet, not at its
edge"""


def solid_share(g: np.ndarray, outline: np.ndarray, ink: float, paper: float) -> float:
    """The share of the region inside `outline` (a contour in `g`'s pixels) darker than half-way from `ink` to
    `paper`: about 1 for a filled shape (also one the local threshold hollowed), far less for an outline."""
    inside = np.zeros(g.shape, np.uint8)
    cv2.drawContours(inside, [outline], -1, 255, cv2.FILLED)
    n = cv2.countNonZero(inside)
    if n == 0:
        return 0.0
    dark = cv2.inRange(g, 0, (ink + paper) / 2)
    return cv2.countNonZero(cv2.bitwise_and(inside, dark)) / n


def whole_sheet(g: np.ndarray, box: Box, reach: float) -> str:
    """"sheet" if the mark in `box` (in `g`'s pixels) lies on a whole sheet ending within `reach` x the box's longer
    side beyond the box, inside the image; else the first test that failed: "faint", "no paper", "runs on" (past
    the reach or out of the frame), "not solid", "corners", "small", "not plain" or "off the
    sheet"."""
    x, y, w, h = box
    side = max(w, h)
    m = math.ceil(reach * side) + 2
    x0, y0, x1, y1 = max(0, x - m), max(0, y - m), min(g.shape[1], x + w + m), min(g.shape[0], y + h + m)
    inner = g[y : y + h, x : x + w]
    ink, paper = (float(v) for v in np.percentile(inner, (5, 90)))
    if paper - ink < MIN_CONTRAST:
        return "faint"
    tol = max(MIN_TOLERANCE, TOLERANCE * (paper - ink))
    window = g[y0:y1, x0:x1]
    light = cv2.inRange(window, max(0.0, paper - tol), min(255.0, paper + tol))
    edge = cv2.dilate(cv2.Canny(cv2.GaussianBlur(window, (3, 3), 0), *EDGES), np.ones((3, 3), np.uint8))
    n, labels = cv2.connectedComponents(cv2.bitwise_and(light, cv2.bitwise_not(edge)), connectivity=4)
    in_box = labels[y - y0 : y - y0 + h, x - x0 : x - x0 + w]
    counts = np.bincount(in_box[in_box > 0], minlength=n)
    if n <= 1 or counts.sum() == 0:
        return "no paper"
    sheet = (labels == int(np.argmax(counts))).astype(np.uint8)
    # the window ends at the reach or at the frame's edge: paper that touches it runs on (a wall, or out of view)
    if sheet[0].any() or sheet[-1].any() or sheet[:, 0].any() or sheet[:, -1].any():
        return "runs on"
    sheet[y - y0 : y - y0 + h, x - x0 : x - x0 + w] |= (inner < (ink + paper) / 2).astype(np.uint8)  # the mark too
    sheet = cv2.morphologyEx(sheet, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))  # over the edges' seams
    outline = max(cv2.findContours(sheet, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0], key=cv2.contourArea)
    hull = cv2.convexHull(outline)
    if cv2.contourArea(outline) < MIN_SOLIDITY * max(cv2.contourArea(hull), 1.0):
        return "not solid"
    if len(cv2.approxPolyDP(hull, 0.05 * cv2.arcLength(hull, True), True)) not in CORNERS:
        return "corners"
    if cv2.contourArea(hull) < (WIDER * side) ** 2:
        return "small"
    # other things on it (words, pictures, fingers over its edge): what the hull holds that is not paper or the mark
    other = np.zeros_like(sheet)
    cv2.drawContours(other, [hull], -1, 1, cv2.FILLED)
    area = cv2.countNonZero(other)
    other[sheet > 0] = 0
    other[max(0, y - y0 - 2) : y - y0 + h + 2, max(0, x - x0 - 2) : x - x0 + w + 2] = 0
    if cv2.countNonZero(other) > PLAIN * area:
        return "not plain"
    corners = ((x - x0, y - y0), (x - x0 + w, y - y0), (x - x0, y - y0 + h), (x - x0 + w, y - y0 + h))
    inside = min(cv2.pointPolygonTest(hull, (float(cx), float(cy)), True) for cx, cy in corners)
    return "sheet" if inside >= INSIDE * side else "off the sheet"
