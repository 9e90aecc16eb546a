"""Round vision34's speed condition (f): the first FRAMES frames of a held-out seed, detected by the base and the
variant in turn, PASSES times each in one process, one thread; prints each pass's frames per CPU-second and the
medians. Round vision35 passes its variant's settings as SETTINGS (default: vision34's, hand_triangle=0.8; the base is
always the default detector of the code run).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision34_speed.py SEED [FRAMES] [PASSES] [SETTINGS]"""
import statistics
import sys
import time

import cv2

from services.vision.detector import MarkDetector, parse_settings
from services.vision.heldout import HeldOutGenerator
from services.vision.verifier import SHAPES

cv2.setNumThreads(1)
seed = int(sys.argv[1])
n = int(sys.argv[2]) if len(sys.argv) > 2 else 400
passes = int(sys.argv[3]) if len(sys.argv) > 3 else 5
settings = sys.argv[4] if len(sys.argv) > 4 else "hand_triangle=0.8"
gen = HeldOutGenerator(seed=seed)
shapes = (*SHAPES, None)
frames = [gen.frame(shapes[i % 4])[0] for i in range(n)]
dets = {"base": MarkDetector(), "variant": MarkDetector(parse_settings(settings))}
rates: dict[str, list[float]] = {k: [] for k in dets}
for det in dets.values():  # warm up
    for f in frames[:20]:
        det.detect(f)
for _ in range(passes):
    for name, det in dets.items():
        c0 = time.process_time()
        for f in frames:
            det.detect(f)
        rates[name].append(n / (time.process_time() - c0))
for name, r in rates.items():
    print(name, [round(v, 1) for v in r], "median", round(statistics.median(r), 1))
print("variant / base", round(statistics.median(rates["variant"]) / statistics.median(rates["base"]), 3))
