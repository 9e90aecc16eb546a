"""Stop 75's look (tuning frames only; nothing in the detector came of it): is a whole card found around the filled
triangles the detector misses? For every candidate over a missed filled triangle, and every clutter candidate the
shape tests claimed as a triangle or the verifier found likeliest a triangle (at 0.05 or more), `card_around` looks
for a card that ends within REACH x the mark's size beyond its box. Prints the counts and, per missed triangle, why
the card was not found.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/stop75_card_outline.py SEED FRAMES [REACH] [EDGE_LOW EDGE_HIGH]
Stop 75 ran seed 7129, 600 frames (exact, every triangle filled), reach 0.9, Canny 20 / 50 (and 10 / 25, 6 / 15)."""

import math
import sys
from dataclasses import replace

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision.detector import MarkDetector, box_overlap, to_gray
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.training import IOU, iou
from services.vision.verifier import CLASSES, MODEL_PATH, Verifier, claim

cv2.setNumThreads(1)
MIN_CONTRAST, TOLERANCE, MIN_TOLERANCE, MIN_SOLIDITY, CORNERS = 35.0, 0.25, 10.0, 0.8, (4, 5)


def card_around(g: np.ndarray, box: tuple[int, int, int, int], reach: float, edges: tuple[int, int]) -> str:
    """"card" if the mark in `box` lies on a whole card: a region of about the paper's grey (the box's 90th
    percentile; its 5th is the ink), parted from the background by Canny's edges, that ends within `reach` x the
    box's longer side beyond the box on every side and inside the image, fills MIN_SOLIDITY of its hull, has four
    or five corners and holds the box's centre; else the first test that failed."""
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
    edge = cv2.dilate(cv2.Canny(cv2.GaussianBlur(window, (3, 3), 0), *edges), np.ones((3, 3), np.uint8))
    n, labels = cv2.connectedComponents(cv2.bitwise_and(light, cv2.bitwise_not(edge)), connectivity=4)
    in_box = labels[y - y0 : y - y0 + h, x - x0 : x - x0 + w]
    counts = np.bincount(in_box[in_box > 0], minlength=n)
    if n <= 1 or counts.sum() == 0:
        return "no paper"
    card = (labels == int(np.argmax(counts))).astype(np.uint8)
    if card[0].any() or card[-1].any() or card[:, 0].any() or card[:, -1].any():
        return "runs on"  # beyond the reach (a wall, a background of its grey) or out of the frame
    card[y - y0 : y - y0 + h, x - x0 : x - x0 + w] |= (inner < (ink + paper) / 2).astype(np.uint8)  # the mark too
    card = cv2.morphologyEx(card, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))  # over the edges' seams
    outline = max(cv2.findContours(card, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0], key=cv2.contourArea)
    hull = cv2.convexHull(outline)
    if cv2.contourArea(outline) < MIN_SOLIDITY * max(cv2.contourArea(hull), 1.0):
        return "not solid"
    if len(cv2.approxPolyDP(hull, 0.05 * cv2.arcLength(hull, True), True)) not in CORNERS:
        return "corners"
    centre = (x - x0 + w / 2, y - y0 + h / 2)
    return "card" if cv2.pointPolygonTest(hull, centre, True) >= 0.25 * side else "off the card"


def main() -> None:
    seed, n = int(sys.argv[1]), int(sys.argv[2])
    reach = float(sys.argv[3]) if len(sys.argv) > 3 else 0.9
    edges = (int(sys.argv[4]), int(sys.argv[5])) if len(sys.argv) > 5 else (20, 50)
    verifier, det = Verifier.load(MODEL_PATH), MarkDetector()
    raw = MarkDetector(replace(det.config, verify=False, danger_first=False))
    gen = SceneGenerator(seed=seed, variation=Variation(filled_triangle=1.0))
    k = CLASSES.index(Shape.TRIANGLE)
    missed: dict[int, str] = {}
    clutter = clutter_card = 0
    for i in range(n):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE, None)[i % 4]
        img, labels = gen.render(gen.scene(shape))
        g, mark = to_gray(img), (labels[0] if labels else None)
        if shape is Shape.TRIANGLE and not any(
            d.shape is shape and box_overlap(d.box, mark.box) >= 0.5 for d in det.detect(img)
        ):
            missed[i] = card_around(g, mark.box, reach, edges)
        for c in raw.candidates(img):
            p = verifier.probabilities(c.crops[None], claim(c.shape)[None])[0]
            likely = c.shape is Shape.TRIANGLE or (c.shape is None and int(np.argmax(p[:3])) == k)
            if likely and p[k] >= 0.05 and (mark is None or iou(c.box, mark.box) < IOU):
                clutter += 1
                clutter_card += card_around(g, c.box, reach, edges) == "card"
    found = sum(v == "card" for v in missed.values())
    print(f"seed {seed}, {n} frames, reach {reach}, Canny {edges}: a whole card around {found} of {len(missed)} "
          f"missed filled triangles and {clutter_card} of {clutter} clutter candidates")
    for i, why in missed.items():
        print(f"  frame {i}: {why}")


if __name__ == "__main__":
    main()
