"""Round vision37: where the X and triangles refused by their shape confidence alone were (tuning seeds 7093 exact and
7091 half drawn by hand, 600 frames each, the generator's own frames, with confidence_rescue on, a worktree of 7364566):
per refusal, the frame, the shape, the label, whether the refusal was on the label and whether the frame's mark was
found all the same. As run; the option was removed after the probe."""
import sys, numpy as np
sys.path.insert(0, '/tmp/s64/wtp')
from services.vision.detector import MarkDetector, DetectorConfig, box_overlap, _up
from services.vision.synthetic import SceneGenerator, Variation
from schemas.messages import Shape
events = []
orig_r = MarkDetector._rescuable
def r(self, shape, level, i):
    out = orig_r(self, shape, level, i)
    if self._why == "confidence" and shape in (Shape.X, Shape.TRIANGLE):
        x, y, w, h = (int(v) for v in level.stats[i][:4])
        events.append((shape, _up((x, y, w, h), level.f)))
    return out
MarkDetector._rescuable = r
base = MarkDetector(DetectorConfig())
det = MarkDetector(DetectorConfig(confidence_rescue=True))
shapes = [Shape.X, Shape.O, Shape.TRIANGLE, None]
rows = []
for seed, hand in ((7093, 0.0), (7091, 0.5)):
    g = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
    for i in range(600):
        s = shapes[i % 4]
        img, labels = g.render(g.scene(s))
        events.clear()
        found = det.detect(img)
        if events:
            lab = labels[0] if labels else None
            for shape, box in events:
                on_label = lab is not None and box_overlap(box, lab.box) >= 0.3
                found_it = lab is not None and any(box_overlap(d.box, lab.box) >= 0.5 and d.shape == lab.shape for d in found)
                rows.append((seed, i, shape.value, lab.shape.value if lab else None, on_label, found_it))
for row in rows: print(row)
