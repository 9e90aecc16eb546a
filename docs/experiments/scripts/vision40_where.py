"""Round vision40's count, mark by mark: for every true triangle of the tuning frames that today's detector misses
(the bench's rule), the stage the stage breakdown charges it to (`bench/vision_stages.charged`) and which candidates
overlap it (IoU >= 0.4) without the verifier and `danger_first`: claimed TRIANGLE and kept by the card tests (what
the second network is asked about), claimed TRIANGLE and refused by them, claimed as another shape, or loose (no
shape claimed). Frames rendered in sequence.
    PYTHONPATH=$W .venv/bin/python docs/experiments/scripts/vision40_where.py SEED HAND FRAMES"""

import sys
from collections import Counter
from dataclasses import replace

import cv2

from bench.vision_stages import ORDER, charged
from schemas.messages import Shape
from services.vision.detector import MarkDetector, box_overlap
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.training import IOU, iou

cv2.setNumThreads(1)
seed, hand, n = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
det = MarkDetector()
raw = MarkDetector(replace(det.config, verify=False, danger_first=False))
gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
stages: Counter[str] = Counter()
kinds: Counter[str] = Counter()
triangles = 0
for i in range(n):
    img, labels = gen.render(gen.scene(ORDER[i % len(ORDER)]))
    if not labels or labels[0].shape is not Shape.TRIANGLE:
        continue
    mark, triangles = labels[0], triangles + 1
    if any(d.shape is Shape.TRIANGLE and box_overlap(d.box, mark.box) >= 0.5 for d in det.detect(img)):
        continue
    found, traced = det.trace(img)
    stages[charged(found, traced, Shape.TRIANGLE, mark.box)] += 1
    near = [c for c in raw.candidates(img) if iou(c.box, mark.box) >= IOU]
    kind = (
        "claimed, kept" if any(c.shape is Shape.TRIANGLE and c.kept for c in near)
        else "claimed, refused" if any(c.shape is Shape.TRIANGLE for c in near)
        else "another shape" if any(c.shape is not None for c in near)
        else "loose only" if near
        else "no candidate"
    )
    kinds[kind] += 1
missed = sum(stages.values())
print(f"seed {seed}, hand {hand}: {triangles} triangles, {missed} missed")
print("  charged to:", dict(stages.most_common()))
print("  candidates on them:", dict(kinds.most_common()))
