"""Time detect() over cached frames, single thread; dump detections for an exactness check.
usage: PYTHONPATH=<tree> python ab.py frames.npy out.pkl [passes] [settings...]"""
import pickle, sys, time
import cv2, numpy as np
import services.vision.detector as D
cv2.setNumThreads(1)
frames = np.load(sys.argv[1], mmap_mode="r")
out = sys.argv[2]
passes = int(sys.argv[3]) if len(sys.argv) > 3 else 3
cfg = D.parse_settings(sys.argv[4:]) if len(sys.argv) > 4 else D.DetectorConfig()
det = D.MarkDetector(cfg)
frames = [np.array(f) for f in frames]
res = [det.detect(f) for f in frames]
best = []
for _ in range(passes):
    c0 = time.process_time()
    for f in frames:
        det.detect(f)
    best.append(len(frames) / (time.process_time() - c0))
pickle.dump([[(d.shape.value, round(d.confidence, 9), tuple(d.box)) for d in r] for r in res], open(out, "wb"))
print(D.__file__, "fps(cpu) passes:", [round(b, 1) for b in best], "max", round(max(best), 1), "n_det", sum(map(len, res)))
