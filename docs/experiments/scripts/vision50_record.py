"""Round vision50's recording: every TRIANGLE a component without a hole becomes (claimed by the shape tests or named by
the verifier as a loose candidate) that passes the context tests, with `open_side` of its outline at reaches
0.05 / 0.08 / 0.12 (cover and shade) and its solidity, labelled true when it is on the frame's triangle (the bench's
box rule) and reported when the frame's detections hold it. ONLY=f1,f2,... detects on those frames only (the others
are drawn and skipped: the same frames). Run on tuning seeds 7180 (exact), 7181 and 7182 (hand 1) and on diagnostic
blind seeds 853 and 863 (looked at: never used for a decision), 2,000 frames each; the shade (as committed) on the
frames holding a row with a cover under 0.8 (ONLY), after a first shade measure that took the paper inside the
triangle (a filled triangle's ink) was dropped.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision50_record.py tuning|blind SEED FRAMES HAND OUT.json"""
import json, sys
from pathlib import Path
import cv2
import numpy as np
from schemas.messages import Shape
from services.vision import detector as D
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.blind import BlindGenerator
cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)
split, seed, n, hand, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
REACH = (0.05, 0.08, 0.12)


class Recording(D.MarkDetector):
    def __init__(self):
        super().__init__()
        self.frame_rows = []

    def _finish(self, level, i, blob, own, shape, conf, box=None):
        det = super()._finish(level, i, blob, own, shape, conf, box)
        if det is not None and shape is Shape.TRIANGLE and not blob.holes:
            loose = sys._getframe(1).f_code.co_name == "_verify"
            bx, by = (box if box is not None else tuple(int(v) for v in level.stats[i][:2]))[:2]
            outer = blob.outer + np.array([bx - 1, by - 1], np.int32)
            sides = [D.open_side(level.g, outer, r) for r in REACH]
            self.frame_rows.append(dict(box=list(D._up(det.box, level.f)), loose=loose, f=level.f, conf=conf,
                                        cover=[o.cover if o else -1 for o in sides], shade=[o.shade if o else -1 for o in sides],
                                        solidity=blob.area / max(1.0, cv2.contourArea(cv2.convexHull(blob.outer)))))
        return det


det = Recording()
if split == "blind":
    gen = BlindGenerator(seed=seed)
    def frame(t):
        img, lab = gen.frame(t)
        return img, (None if lab is None else (lab.shape, lab.box))
else:
    import os
    from services.vision.synthetic import DISTRACTORS
    extra = tuple(k for k in os.environ.get('EXTRA', '').split(',') if k)
    sg = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand, kinds=DISTRACTORS + extra))
    def frame(t):
        img, labels = sg.render(sg.scene(t))
        m = labels[0] if labels else None
        return img, (None if m is None else (m.shape, m.box))
rows = []
import os
ONLY = {int(v) for v in os.environ.get('ONLY', '').split(',') if v}
for k in range(n):
    t = ORDER[k % 4]
    img, lab = frame(t)
    if ONLY and k not in ONLY:
        continue
    det.frame_rows = []
    found = det.detect(img)
    for r in det.frame_rows:
        r["frame"] = k
        r["truth"] = t.name if t else "none"
        r["reported"] = any(d.shape is Shape.TRIANGLE and D.box_overlap(d.box, tuple(r["box"])) >= 0.5 for d in found)
        r["true"] = lab is not None and lab[0] is Shape.TRIANGLE and D.box_overlap(tuple(r["box"]), lab[1]) >= 0.5
        rows.append(r)
Path(out).write_text(json.dumps(rows))
rep = [r for r in rows if r["reported"]]
print(len(rows), "rows,", len(rep), "reported:", sum(r["true"] for r in rep), "true,", sum(not r["true"] for r in rep), "false")
for j, reach in enumerate(REACH):
    for bar in (0.3, 0.4, 0.5, 0.6):
        print(f"reach {reach} bar {bar}: true under {sum(r['true'] and r['cover'][j] < bar for r in rep)}, "
              f"false under {sum((not r['true']) and r['cover'][j] < bar for r in rep)}")
for r in rep:
    if not r["true"] or min(r["cover"]) < 0.6:
        print("true " if r["true"] else "false", r["frame"], r["truth"], r["box"], "loose" if r["loose"] else "claimed",
              round(r["conf"], 3), [round(c, 2) for c in r["cover"]], [round(c, 2) for c in r["shade"]], round(r["solidity"], 2))
