"""Round vision39: what the marks lost at "no component" look like (tuning generator only).

For every mark that `bench/vision_stages.py` would charge to "no component" (no traced component matches its box
with IoU >= 0.4, and no detection found it), this looks at each pyramid level's binarisation directly: the
component holding most of the dark pixels inside the mark's box, its box against the mark's, and the scene's
conditions. A mark is then "merged" (that component's box is over 1.6 x the mark's: joined to a finger, the card
edge or the background), "broken" (under 0.6 x: the strokes fall apart or only part is dark), "empty" (no dark
pixel in the box at any level: too faint for the threshold) or "near" (a component of about its size that still
misses the box: IoU 0.2-0.4, a tilted or blurred box). Per mark it prints one JSON line; a summary at the end.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision39_nocomp.py SEED FRAMES HAND [--set k=v ...]
"""

from __future__ import annotations

import json
import math
import sys
from collections import Counter

import cv2
import numpy as np

from bench.vision_stages import ORDER, charged
from services.vision.detector import MarkDetector, parse_settings, to_gray
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.training import iou


def level_images(gray: np.ndarray, levels) -> list[tuple[int, np.ndarray, np.ndarray]]:
    out = []
    for f, block, *_ in levels:
        if f == 1:
            g = cv2.GaussianBlur(gray, (3, 3), 0)
        else:
            g = cv2.resize(gray, (gray.shape[1] // f, gray.shape[0] // f), interpolation=cv2.INTER_AREA)
        binary = cv2.adaptiveThreshold(g, 255, cv2.ADAPTIVE_THRESH_MEAN_C, cv2.THRESH_BINARY_INV, block, 12.0)
        out.append((f, g, binary))
    return out


def why(gray: np.ndarray, box, levels) -> dict:
    x, y, w, h = box
    best: dict = {"kind": "empty", "iou": 0.0}
    for f, g, binary in level_images(gray, levels):
        x0, y0 = max(0, x // f), max(0, y // f)
        x1, y1 = min(g.shape[1], (x + w) // f + 1), min(g.shape[0], (y + h) // f + 1)
        if x1 - x0 < 3 or y1 - y0 < 3:
            continue
        n, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=8)
        inside = labels[y0:y1, x0:x1]
        ids, counts = np.unique(inside[inside > 0], return_counts=True)
        if len(ids) == 0:
            continue
        k = int(ids[np.argmax(counts)])
        cx, cy, cw, ch = (int(v) * f for v in stats[k, :4])
        score = iou((cx, cy, cw, ch), box)
        ratio = (cw * ch) / max(w * h, 1)
        share = float(counts.max()) / max(int((inside > 0).sum()), 1)
        if score > best["iou"] or best["kind"] == "empty":
            kind = "merged" if ratio > 1.6 else "broken" if ratio < 0.6 else "near"
            best = {"kind": kind, "iou": round(score, 3), "ratio": round(ratio, 2), "share": round(share, 2),
                    "f": f, "pieces": int(len(ids))}
    return best


def main() -> None:
    seed, frames, hand = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    settings = sys.argv[sys.argv.index("--set") + 1:] if "--set" in sys.argv else []
    cfg = parse_settings(settings)
    cv2.setNumThreads(1)
    gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
    det = MarkDetector(cfg)
    kinds: Counter[str] = Counter()
    marks: Counter[str] = Counter()
    for i in range(frames):
        truth = ORDER[i % len(ORDER)]
        scene = gen.scene(truth)
        img, labels = gen.render(scene)
        if not labels:
            continue
        lab = labels[0]
        marks[lab.shape.value] += 1
        found, traced = det.trace(img)
        if charged(found, traced, lab.shape, lab.box) != "no component":
            continue
        gray = to_gray(img)
        row = why(gray, lab.box, cfg.levels)
        paper, ink = np.array(scene.paper, float), np.array(scene.ink, float)
        row.update({
            "frame": i, "shape": lab.shape.value, "size": int(max(lab.box[2:])), "stroke": round(scene.stroke, 3),
            "blur": round(scene.blur[0], 1), "fingers": scene.fingers, "finger_gap": round(scene.finger_gap, 2),
            "border": round((min(scene.card) - 1) / 2, 3), "light": round(float(np.median(scene.light)), 2),
            "contrast": round(float(paper.mean() - ink.mean()), 1), "by_hand": scene.by_hand is not None,
            "tilt": round(math.hypot(*scene.tilt), 1), "filled": scene.filled, "noise": round(scene.noise, 1),
            "jpeg": scene.jpeg,
        })
        kinds[f"{lab.shape.value} {row['kind']}"] += 1
        print(json.dumps(row), flush=True)
    print(json.dumps({"seed": seed, "frames": frames, "hand": hand, "marks": dict(marks), "kinds": dict(sorted(kinds.items()))}))


if __name__ == "__main__":
    main()
