"""Round vision52's recording: every O the detector reports (today's default, `o_islands` 0), with the share of its box
that islands of ink in its hole cover (`detector.hole_islands`) and whether it is a true O.

Usage: PYTHONPATH=. python vision52_record.py tuning|blind SEED FRAMES HAND OUT.json
(HAND: --hand-drawn and --hand-variety for the tuning generator; frames cycle X, O, TRIANGLE, none.)"""
import json
import sys
from pathlib import Path

import cv2

from schemas.messages import Shape
from services.vision import detector as D
from services.vision.blind import BlindGenerator
from services.vision.synthetic import SceneGenerator, Variation

cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)
split, seed, n, hand, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
det = D.MarkDetector()
if split == "blind":
    gen = BlindGenerator(seed=seed)

    def frame(t):
        img, lab = gen.frame(t)
        return img, (None if lab is None else (lab.shape, lab.box))
else:
    sg = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))

    def frame(t):
        img, labels = sg.render(sg.scene(t))
        m = labels[0] if labels else None
        return img, (None if m is None else (m.shape, m.box))

rows = []
for k in range(n):
    t = ORDER[k % 4]
    img, lab = frame(t)
    for d in det.detect(img):
        if d.shape is not Shape.O:
            continue
        rows.append(dict(
            frame=k, truth=t.name if t else "none", box=list(d.box), conf=round(d.confidence, 3),
            true=lab is not None and lab[0] is Shape.O and D.box_overlap(d.box, lab[1]) >= 0.5,
            islands=round(D.hole_islands(det._gray, d.box), 4),
        ))
Path(out).write_text(json.dumps(rows))
print(len(rows), "O reported:", sum(r["true"] for r in rows), "true;",
      "islands over 0:", [(r["true"], r["islands"]) for r in rows if r["islands"] > 0])
