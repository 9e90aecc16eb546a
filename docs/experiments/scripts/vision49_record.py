"""Round vision49's recording: every O the detector reports, with `middle_ink` of its box at middles 0.3 / 0.4 / 0.5, labelled
true when it is on the frame's O mark (the bench's box rule). Run on tuning seed 7175 (1,000 frames) and on diagnostic
blind seed 853 (2,000 frames; looked at: never used for a decision).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision49_record.py tuning|blind SEED FRAMES HAND OUT.json"""
import json, sys
from pathlib import Path
import cv2, numpy as np
from schemas.messages import Shape
from services.vision import detector as D
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.blind import BlindGenerator
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
for i in range(n):
    t = ORDER[i % 4]
    img, lab = frame(t)
    found = det.detect(img)
    gray, _ = D.working_gray(img, det.config.max_side)
    for d in found:
        if d.shape is not Shape.O:
            continue
        true = lab is not None and lab[0] is Shape.O and D.box_overlap(d.box, lab[1]) >= 0.5
        ink = [D.middle_ink(gray, d.box, m) for m in (0.3, 0.4, 0.5)]
        rows.append(dict(frame=i, truth=t.name if t else "none", true=true, conf=d.confidence, box=list(d.box), ink=ink))
Path(out).write_text(json.dumps(rows))
tr = [r for r in rows if r["true"]]; fa = [r for r in rows if not r["true"]]
print(len(tr), "true O,", len(fa), "false O")
for r in fa: print("false", r["frame"], r["truth"], r["box"], round(r["conf"], 3), [round(v, 3) for v in r["ink"]])
import collections
for m in range(3):
    v = sorted(r["ink"][m] for r in tr)
    print("middle", (0.3, 0.4, 0.5)[m], "true O ink: >0.02:", sum(x > 0.02 for x in v), ">0.05:", sum(x > 0.05 for x in v), ">0.1:", sum(x > 0.1 for x in v), ">0.2:", sum(x > 0.2 for x in v))
