"""Round vision50b's recording: every proposed TRIANGLE that reaches the open-side test (every other test passed), with
`open_side` of `box_outline` of its box (cover, shade; None: no outline to judge), labelled true when it is on the
frame's triangle (the bench's box rule) and reported when the frame's detections hold a TRIANGLE over it. The
detector is today's default (the test recorded, never applied). Run on tuning seeds 7180 (exact), 7181 and 7182 (hand
1) and on diagnostic blind seeds 853 and 863 (looked at: never used for a decision), 2,000 frames each.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision50b_record.py tuning|blind SEED FRAMES HAND OUT.json"""
import json, sys
from dataclasses import replace
from pathlib import Path
import cv2
from schemas.messages import Shape
from services.vision import detector as D
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.blind import BlindGenerator
cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)
split, seed, n, hand, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]


class Recording(D.MarkDetector):
    def __init__(self):
        super().__init__(replace(D.DetectorConfig(), propose_open_side=1.0))
        self.frame_rows = []

    def open_proposal(self, gray, box):
        outline = D.box_outline(gray, box)
        side = None if outline is None else D.open_side(gray, outline)
        self.frame_rows.append(dict(box=list(box), cover=None if side is None else side.cover,
                                    shade=None if side is None else side.shade))
        return False


det = Recording()
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
print(len(rows), "proposed triangles judged,", len(rep), "reported:", sum(r["true"] for r in rep), "true,",
      sum(not r["true"] for r in rep), "false;", sum(r["cover"] is None for r in rep), "with no outline to judge")
for r in rep:
    if not r["true"] or (r["cover"] is not None and r["cover"] < 0.75):
        print("true " if r["true"] else "false", r["frame"], r["truth"], r["box"],
              None if r["cover"] is None else (round(r["cover"], 2), round(r["shade"], 2)))
