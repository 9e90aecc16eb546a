"""Round vision47c's prototype, tuning data and round vision47's probe only (dropped, no rule, no held-out run): how
elliptical the outline of a proposed O's ring is, for the proposed O the sure peak alone keeps (vision47_record.py's
recording with one more figure, `res`: the mean |r - 1| of the outer contour of the ring's ink, split at half-way from
the ring's ink to the middle's paper as `middle_ink` splits it, against its fitted ellipse, `detector._ellipse_residual`;
9 where no contour matches the box). An outlined square gives about 0.09, a ring about 0.005 (drawn and blurred).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47c_outline.py SEED FRAMES HAND OUT.json
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47c_outline.py probe SEED FRAMES OUT.json"""

import importlib.util
import math
from pathlib import Path

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision import detector as D
from services.vision.verifier import CLASSES

spec = importlib.util.spec_from_file_location("record", Path(__file__).with_name("vision47_record.py"))
assert spec is not None and spec.loader is not None
record = importlib.util.module_from_spec(spec)
spec.loader.exec_module(record)


def outline_residual(g: np.ndarray, box: tuple[int, int, int, int], middle: float = 0.4, pad: float = 0.2) -> float:
    x, y, w, h = box
    cx, cy = x + w / 2, y + h / 2
    x0, y0 = max(0, math.floor(cx - (0.5 + pad) * w)), max(0, math.floor(cy - (0.5 + pad) * h))
    x1, y1 = min(g.shape[1], math.ceil(cx + (0.5 + pad) * w)), min(g.shape[0], math.ceil(cy + (0.5 + pad) * h))
    if x1 - x0 < 6 or y1 - y0 < 6:
        return 9.0
    yy, xx = np.ogrid[y0:y1, x0:x1]
    e = ((xx + 0.5 - cx) / max(1.0, w / 2)) ** 2 + ((yy + 0.5 - cy) / max(1.0, h / 2)) ** 2
    roi = g[y0:y1, x0:x1]
    inner, band = roi[e <= middle**2], roi[(e >= 0.55**2) & (e <= 1.1**2)]
    if inner.size < 4 or band.size < 4:
        return 9.0
    paper, ink = float(np.median(inner)), float(np.percentile(band, 10))
    dark = ((roi < (paper + ink) / 2) * 255).astype(np.uint8)
    contours, _ = cv2.findContours(dark, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    best, score = None, 0.3  # the contour whose bounding box overlaps the proposal's most (IoU), at least 0.3
    bx0, by0 = x - x0, y - y0
    for c in contours:
        rx, ry, rw, rh = cv2.boundingRect(c)
        inter = max(0, min(bx0 + w, rx + rw) - max(bx0, rx)) * max(0, min(by0 + h, ry + rh) - max(by0, ry))
        iou = inter / float(w * h + rw * rh - inter)
        if iou > score:
            best, score = c, iou
    r = None if best is None else D._ellipse_residual(best)
    return 9.0 if r is None else r


class Outline(record.Recording):
    def _judged_proposals(self, gray: np.ndarray, found: list[D.Detection]):  # type: ignore[no-untyped-def]
        judged = D.MarkDetector._judged_proposals(self, gray, found)
        k = CLASSES.index(Shape.O)
        for p, row in judged:
            if p.shape is Shape.O and p.score >= 0.6 and 0.75 <= row[k] < 0.99:
                f = self._crop_level(p.box)
                g, b = self._greys.get(f, gray), D._down(p.box, f)
                self.rows.append({"peak": p.score, "prob": float(row[k]), "box": list(p.box), "level": f,
                                  "ink": [D.middle_ink(g, b, m) for m in record.MIDDLES], "res": outline_residual(g, b)})
        return judged


if __name__ == "__main__":
    record.Recording = Outline
    record.main()
