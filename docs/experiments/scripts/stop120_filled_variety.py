"""Stop 120's second tuning probe: one filled triangle off any card over each mark-free tuning frame, drawn in one of
several ways the tuning generator does not draw (its own OpenCV drawing code and seeds, never the held-out
generator's): which ways today's detector takes for a TRIANGLE.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/stop120_filled_variety.py SEED FRAMES [KEY=VALUE ...]

Styles: "equilateral" (as the tuning generator's clutter, on the scene), "uneven" (any triangle with no angle under
25 degrees), "tall" (isosceles, its apex angle 25-50 degrees: a pennant, a road sign's arrow), "rounded" (corners
rounded by a fifth of its size, as a printed sign's), "wide wall" (equilateral on a plain light wall that runs on
past five times its size on every side), "soft" (its edges blurred by a tenth of its size: out of focus). Each is
drawn into the scene before the camera's light, blur, noise and JPEG, as the generator's own clutter is (a first
version pasted it on the finished frame, sharper and cleaner than anything else in it: 29 taken on seeds 1 and 2
against this one's 24, on frames that differ in their noise). Each is counted as "bare" (no clutter of the scene
within its own size of it: on a photograph or the procedural scene) or "over clutter" (where a decoy card or a sign
under it would make it a triangle on a card, a mark).
Prints one JSON line: per style and place, the triangles drawn and the frames where a TRIANGLE lies on it that the
frame without it did not have.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from collections import Counter

import cv2
import numpy as np

from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator

STYLES = ("equilateral", "uneven", "tall", "rounded", "wide wall", "soft")


def vertices(rng: np.random.Generator, style: str, c: np.ndarray, size: float) -> np.ndarray:
    """Three corners about `c`, `size` across."""
    turn = rng.uniform(0, 2 * math.pi)
    if style == "uneven":
        while True:
            p = rng.uniform(-0.5, 0.5, (3, 2)) * size
            sides = [p[(k + 1) % 3] - p[k] for k in range(3)]
            angles = [math.degrees(math.acos(np.clip(np.dot(-sides[k - 1], sides[k]) / (
                np.linalg.norm(sides[k - 1]) * np.linalg.norm(sides[k]) + 1e-9), -1, 1))) for k in range(3)]
            if min(angles) >= 25 and np.ptp(p, axis=0).max() >= 0.6 * size:
                return c + p
    if style == "tall":
        apex = math.radians(rng.uniform(25, 50))
        r = size / 2
        pts = np.array([[0.0, -r], [r * math.sin(apex / 2) * 2, r], [-r * math.sin(apex / 2) * 2, r]])
    else:
        r = size / 2
        pts = np.array([[r * math.cos(k * 2 * math.pi / 3), r * math.sin(k * 2 * math.pi / 3)] for k in range(3)])
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    return c + pts @ rot.T


def draw(img: np.ndarray, rng: np.random.Generator, style: str) -> np.ndarray:
    """`img` with one triangle drawn; the triangle's mask."""
    h, w = img.shape[:2]
    size = float(np.exp(rng.uniform(np.log(30), np.log(250))))
    c = np.array([rng.uniform(0.1 * w, 0.9 * w), rng.uniform(0.1 * h, 0.9 * h)])
    ink = tuple(int(v) for v in (rng.integers(0, 70, 3) if rng.random() < 0.6 else rng.integers(0, 256, 3)))
    if style == "wide wall":
        level = int(rng.integers(185, 250))
        cv2.rectangle(img, tuple(int(v) for v in c - 5 * size), tuple(int(v) for v in c + 5 * size),
                      (level, level, level - 8), -1)
    pts = np.round(vertices(rng, style, c, size) * 16).astype(np.int32)
    mask = np.zeros((h, w), np.uint8)
    cv2.fillPoly(mask, [pts], 255, cv2.LINE_AA, shift=4)
    if style == "rounded":
        k = max(3, int(size / 5)) | 1
        mask = cv2.erode(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
        mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
    if style == "soft":
        k = max(3, int(size / 10)) | 1
        mask = cv2.GaussianBlur(mask, (k, k), 0)
    a = mask.astype(np.float32)[:, :, None] / 255.0
    img[:] = np.round(img * (1 - a) + np.array(ink, np.float32) * a).astype(np.uint8)
    return mask > 127


def main(seed: int, frames: int, settings: list[str]) -> dict:
    cv2.setNumThreads(1)
    det = MarkDetector(parse_settings(settings))
    gen, rng = SceneGenerator(seed=seed), np.random.default_rng(seed)
    gen.record = True  # the scene's own clutter, to tell a triangle on the bare background from one over clutter
    drawn: Counter[str] = Counter()
    fooled: Counter[str] = Counter()
    for i in range(frames):
        style = STYLES[i % len(STYLES)]
        scene = gen.scene(None)
        frame, _ = gen.render(scene)
        # drawn into the scene, then lit, blurred, noised and compressed with it, as the generator's own clutter is
        background = scene.background.copy()
        mask = draw(background, rng, style)
        img, _ = gen.render(dataclasses.replace(scene, background=background))
        # over clutter: some clutter within the triangle's own size of it (a decoy card or a sign there would make it
        # a triangle on a card, a mark); else on the bare background (a photograph or the procedural scene)
        ys, xs = np.nonzero(mask)
        reach = max(3, int(max(np.ptp(xs), np.ptp(ys)))) if len(xs) else 3
        near = cv2.dilate(mask.astype(np.uint8), np.ones((reach, reach), np.uint8)) > 0
        where = "over clutter" if any((p.mask & near).any() for p in gen.painted) else "bare"
        drawn[f"{style}, {where}"] += 1
        before = {d.box for d in det.detect(frame) if d.shape.value == "TRIANGLE"}
        for d in det.detect(img):
            x, y, bw, bh = d.box
            cy, cx = min(img.shape[0] - 1, y + bh // 2), min(img.shape[1] - 1, x + bw // 2)
            if d.shape.value == "TRIANGLE" and d.box not in before and mask[cy, cx]:
                fooled[f"{style}, {where}"] += 1
                break
    return {"seed": seed, "frames": frames, "settings": settings,
            "styles": {k: {"drawn": drawn[k], "taken_for_a_triangle": fooled[k]} for k in sorted(drawn)}}


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3:])))
