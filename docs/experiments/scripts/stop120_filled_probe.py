"""Stop 120's tuning probe: filled triangles off any card, as the tuning generator draws them (its "filled_triangle"
clutter: half on a plain light wall that runs on, half straight on the scene), three to six a frame and nothing else
over its backgrounds; which of them today's detector takes for a TRIANGLE, by where it lies and its size. A tuning
tool (`synthetic.py`'s drawing, its own seeds), never the held-out generator's.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/stop120_filled_probe.py SEED FRAMES [KEY=VALUE ...]

Prints one JSON line: the triangles drawn and the false TRIANGLEs on them, by wall or scene and by size (px), and
the false marks that lie on no triangle (the background).
"""

from __future__ import annotations

import json
import sys
from collections import Counter

import cv2
import numpy as np

from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator, Variation

SIZES = (0, 40, 80, 160, 10_000)


def main(seed: int, frames: int, settings: list[str]) -> dict:
    cv2.setNumThreads(1)
    det = MarkDetector(parse_settings(settings))
    gen = SceneGenerator(seed=seed, variation=Variation(kinds=("filled_triangle",), distractors=(3, 6)))
    gen.record = True
    drawn: Counter[str] = Counter()
    false: Counter[str] = Counter()
    elsewhere: Counter[str] = Counter()
    for _ in range(frames):
        img, _ = gen.frame(None)
        where = []
        for p in gen.painted:
            ys, xs = np.nonzero(p.mask)
            # a wall is a rectangle round the triangle: its pixels fill their box, a triangle's about half of it
            wall = len(xs) > 0 and len(xs) >= 0.8 * (np.ptp(xs) + 1) * (np.ptp(ys) + 1)
            where.append((p.mask, "wall" if wall else "scene"))
            drawn["wall" if wall else "scene"] += 1
        for d in det.detect(img):
            x, y, w, h = d.box
            cy, cx = min(img.shape[0] - 1, y + h // 2), min(img.shape[1] - 1, x + w // 2)
            on = [kind for mask, kind in reversed(where) if mask[cy, cx]]
            if on and d.shape.value == "TRIANGLE":
                kind = on[0]
                bin_ = next(f"{lo}-{hi}" for lo, hi in zip(SIZES, SIZES[1:], strict=False) if max(w, h) < hi)
                false[f"{kind} {bin_}"] += 1
                false[kind] += 1
            else:
                elsewhere[f"{d.shape.value} on {'a triangle' if on else 'the background'}"] += 1
    return {"seed": seed, "frames": frames, "settings": settings, "drawn": dict(drawn), "false_triangles": dict(false),
            "other_false_marks": dict(elsewhere)}


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3:])))
