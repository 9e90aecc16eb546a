"""Round vision53's recording: every proposed TRIANGLE the detector reports (today's default), with what round vision50b's
open-side test (`propose_open_side`) says of it when it looks for the proposal's ink in its box and MARGIN x its size
round it (`box_outline`), for several margins, and whether it is a true triangle.

Usage: PYTHONPATH=. python vision53_record.py tuning|blind SEED FRAMES HAND OUT.json
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
MARGINS = (0.1, 0.2, 0.3, 0.4, 0.5)
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

calls: dict[tuple[int, ...], dict[str, bool]] = {}
base = det.open_proposal


def open_proposal(gray, box):
    verdicts = {}
    for m in MARGINS:
        outline = D.box_outline(gray, box, m)
        verdicts[str(m)] = outline is not None and det._two_strokes(gray, outline, det.config.propose_open_side)
    calls[tuple(box)] = verdicts
    return base(gray, box)


det.open_proposal = open_proposal
rows = []
for k in range(n):
    t = ORDER[k % 4]
    img, lab = frame(t)
    calls.clear()
    for d in det.detect(img):
        if d.shape is not Shape.TRIANGLE or tuple(d.box) not in calls:
            continue
        rows.append(dict(
            frame=k, truth=t.name if t else "none", box=list(d.box), conf=round(d.confidence, 3),
            true=lab is not None and lab[0] is Shape.TRIANGLE and D.box_overlap(d.box, lab[1]) >= 0.5,
            refused=calls[tuple(d.box)],
        ))
Path(out).write_text(json.dumps(rows))
for m in MARGINS:
    print(f"margin {m}: {len(rows)} proposed TRIANGLE reported, {sum(r['true'] for r in rows)} true; refused true "
          f"{sum(r['true'] and r['refused'][str(m)] for r in rows)}, false "
          f"{sum(not r['true'] and r['refused'][str(m)] for r in rows)} of {sum(not r['true'] for r in rows)}")
