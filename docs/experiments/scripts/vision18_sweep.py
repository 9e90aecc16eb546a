"""Scratch: baseline detections + every proposal (threshold 0.1) with the verifier's probabilities, per
frame, saved for an offline sweep of the proposal thresholds. Usage: sweep.py SPLIT SEED FRAMES MODEL OUT"""
import sys, pickle, time
import numpy as np, cv2
sys.path.insert(0, '/work/main'); sys.path.insert(0, '/work/main/bench')
from pathlib import Path
from vision_bench import _generator, CLASSES
from services.vision.detector import MarkDetector, DetectorConfig, box_overlap
from services.vision.proposer import Proposer
from services.vision.verifier import crops, claim
cv2.setNumThreads(1)
split, seed, frames, model, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
frame_of = _generator(split, seed)
det = MarkDetector(DetectorConfig())
prop = Proposer.load(Path(model))
rows = []
tp = 0.0
for i in range(frames):
    truth = CLASSES[i % len(CLASSES)]
    img, label, meta = frame_of(truth)
    found = det.detect(img)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    t0 = time.perf_counter()
    props = prop.propose(gray, 0.1)
    tp += time.perf_counter() - t0
    greys = det._greys
    pr = []
    for p in props:
        f = max((f for f in greys if max(p.box[2:]) / f >= 48), default=1)
        g = greys[f]
        pv = det.verifier.probabilities(crops(g, tuple(v // f for v in p.box))[None], claim(None)[None])[0]
        pr.append((p.shape, p.score, p.box, pv))
    rows.append((label, meta, found, pr))
pickle.dump(rows, open(out, 'wb'))
print('proposer ms', tp / frames * 1000)
