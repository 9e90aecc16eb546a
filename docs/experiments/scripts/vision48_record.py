"""Round vision48's recording: every proposed TRIANGLE the verifier keeps (its `propose_thresholds`), with `middle_blob` of
its box (triangle fill, roundness, solidity), labelled true when it is on the frame's TRIANGLE mark (the bench's box rule).
Run on tuning seed 7175 and on diagnostic blind seed 853 (looked at: never used for a decision).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision48_record.py tuning|blind SEED FRAMES HAND OUT.json"""
import json, sys
from pathlib import Path
import cv2, numpy as np
from schemas.messages import Shape
from services.vision import detector as D
from services.vision.proposer import Proposal
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.blind import BlindGenerator
from services.vision.verifier import CLASSES
cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)

class Rec(D.MarkDetector):
    def __init__(self):
        super().__init__(); self.rows = []
    def _judged_proposals(self, gray, found):
        judged = super()._judged_proposals(gray, found)
        k = CLASSES.index(Shape.TRIANGLE)
        for p, row in judged:
            if p.shape is Shape.TRIANGLE and row[k] >= self.config.propose_thresholds[k]:
                b = D.middle_blob(gray, p.box)
                self.rows.append({"peak": p.score, "prob": float(row[k]), "box": list(p.box),
                                  "blob": None if b is None else [b.triangle_fill, b.roundness, b.solidity]})
        return judged

split, seed, n, hand, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
det = Rec()
if split == "blind":
    gen = BlindGenerator(seed=seed)
    frame = lambda t: (lambda r: (r[0], r[1]))(gen.frame(t))
else:
    sg = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
    def frame(t):
        img, labels = sg.render(sg.scene(t))
        m = labels[0] if labels else None
        return img, (None if m is None else (m.shape, m.box))
for i in range(n):
    t = ORDER[i % 4]
    img, lab = frame(t)
    if split == "blind" and lab is not None:
        lab = (lab.shape, lab.box) if hasattr(lab, "shape") else lab
    s = len(det.rows)
    det.detect(img)
    for r in det.rows[s:]:
        r["frame"] = i; r["truth"] = t.name if t else "none"
        r["true"] = lab is not None and lab[0] is Shape.TRIANGLE and D.box_overlap(tuple(r["box"]), lab[1]) >= 0.5
Path(out).write_text(json.dumps(det.rows))
print(len(det.rows), "kept proposed triangles;", sum(r["true"] for r in det.rows), "true")
