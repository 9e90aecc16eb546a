"""Round vision51's recording: every reported X and TRIANGLE, with `notches` of its box (in the frame's working grey) at
several depths (count, widest gap, inner), labelled true when it is on the frame's mark of that shape (box overlap
0.5). Today's default detector (the star test recorded, never applied).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision51_record.py tuning|blind SEED FRAMES HAND OUT.json"""
import json, sys
from pathlib import Path
import cv2
from schemas.messages import Shape
from services.vision import detector as D
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.blind import BlindGenerator
cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)
DEPTHS = (0.06, 0.08, 0.1, 0.12, 0.15)
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
    found = det.detect(img)
    g = det._gray
    for d in found:
        if d.shape is Shape.O:
            continue
        r = dict(frame=k, truth=t.name if t else "none", shape=d.shape.name, box=list(d.box), conf=d.confidence)
        r["true"] = lab is not None and lab[0] is d.shape and D.box_overlap(d.box, lab[1]) >= 0.5
        for dep in DEPTHS:
            nn = D.notches(g, d.box, dep)
            r[str(dep)] = None if nn is None else [nn.count, round(nn.widest_gap, 1), round(nn.inner, 3)]
        rows.append(r)
Path(out).write_text(json.dumps(rows))
print(len(rows), "X/T reported:", sum(r["true"] for r in rows), "true")
