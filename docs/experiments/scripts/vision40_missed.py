"""Round vision40's diagnostic: which candidates the tuning frames' missed triangles leave, and what three networks
give them. Every frame is rendered in sequence (the generator's draws depend on it) and detected with today's
defaults; the candidates are those of the same settings without the verifier and without `danger_first` (every
level): ROWS `kept` (claimed TRIANGLE, the card tests passed: what the second network is asked about), `refused`
(claimed TRIANGLE, the card tests refused: the rescue's) or `loose` (no shape claimed: the verifier names it). Each
candidate overlapping a frame's true triangle (IoU >= 0.4) is "missed" or "found" by the detector (the bench's
rule: a TRIANGLE detection overlapping the mark 0.5); one overlapping no mark is "false". For each group, how many
get TRIANGLE >= 0.8 from the verifier, the committed second network and the network in MODEL (asked with the
candidate's own claim), and their 10/25/50/75/90th percentiles; then the missed rows one by one.
    PYTHONPATH=$W .venv/bin/python docs/experiments/scripts/vision40_missed.py SEED HAND FRAMES MODEL ROWS
HAND is the share drawn by hand and of varied hands (0.5 for the probe's hand seeds, 0 for exact ones)."""

import sys
from dataclasses import replace

import cv2
import numpy as np

from bench.vision_stages import ORDER
from schemas.messages import Shape
from services.vision.detector import MarkDetector, box_overlap
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.training import IOU, iou
from services.vision.verifier import CLASSES, MODEL_PATH, TRIANGLES_PATH, Verifier, claim

cv2.setNumThreads(1)
seed, hand, n, model, which = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
nets = {"verifier": Verifier.load(MODEL_PATH), "committed": Verifier.load(TRIANGLES_PATH), "model": Verifier.load(model)}
det = MarkDetector()
raw = MarkDetector(replace(det.config, verify=False, danger_first=False))
pick = {
    "kept": lambda c: c.shape is Shape.TRIANGLE and c.kept,
    "refused": lambda c: c.shape is Shape.TRIANGLE and not c.kept,
    "loose": lambda c: c.shape is None,
}[which]
k = CLASSES.index(Shape.TRIANGLE)
gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
rows: dict[str, list[list[float]]] = {"missed": [], "found": [], "false": []}
for i in range(n):
    img, labels = gen.render(gen.scene(ORDER[i % len(ORDER)]))
    mark = labels[0] if labels else None
    found = any(
        mark is not None and d.shape is mark.shape and box_overlap(d.box, mark.box) >= 0.5 for d in det.detect(img)
    )
    for c in filter(pick, raw.candidates(img)):
        on_mark = mark is not None and iou(c.box, mark.box) >= IOU
        if on_mark and mark.shape is not Shape.TRIANGLE:
            continue  # a candidate on another mark: neither a triangle nor clutter
        asked = claim(c.shape)[None]
        p = [float(v.probabilities(c.crops[None], asked)[0][k]) for v in nets.values()]
        rows[("found" if found else "missed") if on_mark else "false"].append(p)
print(f"seed {seed}, hand {hand}, {n} frames, {which} candidates")
for group, r in rows.items():
    a = np.array(r).reshape(-1, len(nets))
    print(f"{group} {len(r)}")
    for j, name in enumerate(nets):
        if len(r):
            q = np.round(np.percentile(a[:, j], [10, 25, 50, 75, 90]), 3).tolist()
            print(f"  {name}: >= 0.8 {int((a[:, j] >= 0.8).sum())}; percentiles {q}")
    if group == "missed":
        for p in r:
            print("   ", [round(v, 3) for v in p])
