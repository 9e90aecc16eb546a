"""Round vision36c's speed condition: the first FRAMES frames of a held-out seed, detected in one process, one thread,
PASSES times by three detectors: the base (the code's defaults), a second copy of the base (the control: what the
machine's noise alone gives) and the variant (SETTINGS). Each frame is detected by all three in turn, in an order
rotated frame by frame, and each detector's CPU time is summed over the pass; each pass gives the variant's and the
control's frames per CPU-second over the base's, and the medians of those per-pass ratios are printed. Interleaving
frame by frame takes out the machine's drift, which moved one 5-pass measurement of the base against itself (whole
passes in turn) to 0.773 (round vision36b).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision36c_speed.py SEED FRAMES PASSES SETTINGS"""

import statistics
import sys
import time

import cv2

from services.vision.detector import MarkDetector, parse_settings
from services.vision.heldout import HeldOutGenerator
from services.vision.verifier import SHAPES

cv2.setNumThreads(1)
seed, n, passes, settings = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
gen = HeldOutGenerator(seed=seed)
shapes = (*SHAPES, None)
frames = [gen.frame(shapes[i % 4])[0] for i in range(n)]
dets = {"base": MarkDetector(), "control": MarkDetector(), "variant": MarkDetector(parse_settings(settings))}
for det in dets.values():  # warm up
    for f in frames[:20]:
        det.detect(f)
names = list(dets)
rates: dict[str, list[float]] = {k: [] for k in dets}
for _ in range(passes):
    spent = dict.fromkeys(names, 0.0)
    for i, f in enumerate(frames):  # every frame by all three, in turn: the machine's drift hits all three alike
        for name in names[i % 3 :] + names[: i % 3]:
            c0 = time.process_time()
            dets[name].detect(f)
            spent[name] += time.process_time() - c0
    for name in names:
        rates[name].append(n / spent[name])
for name, r in rates.items():
    print(name, [round(v, 1) for v in r], "median", round(statistics.median(r), 1))
for name in ("control", "variant"):
    ratios = [v / b for v, b in zip(rates[name], rates["base"], strict=True)]
    print(f"{name} / base per pass", [round(v, 3) for v in ratios], "median", round(statistics.median(ratios), 3))
