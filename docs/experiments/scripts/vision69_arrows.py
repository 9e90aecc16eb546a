"""Round vision69's tuning-side arrow count: mark-free frames of the TUNING generator whose clutter is arrows only
(`synthetic.EXTRA_DISTRACTORS`' "arrow": a filled head on a light label or straight on the scene), judged by each
detector named; prints the frames with a false mark and the false marks per shape. Tuning data: a design may be
chosen on it (the arrow probe, vision34_triclutter_probe.py, stays a gate).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision69_arrows.py SEED FRAMES "name KEY=VALUE ..." ..."""
import sys

import cv2

from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator, Variation

cv2.setNumThreads(1)
seed, n = int(sys.argv[1]), int(sys.argv[2])
dets = [(spec.split()[0], MarkDetector(parse_settings(spec.split()[1:]))) for spec in sys.argv[3:]]
gen = SceneGenerator(seed=seed, variation=Variation(kinds=("arrow",), distractors=(2, 5)))
frames = [gen.frame(None)[0] for _ in range(n)]
for name, det in dets:
    hit, false = 0, {"X": 0, "O": 0, "TRIANGLE": 0}
    for img in frames:
        found = det.detect(img)
        hit += bool(found)
        for d in found:
            false[d.shape.value] += 1
    print(f"{name:12s} seed {seed}: frames with a false mark {hit}/{n}  false {false}", flush=True)
