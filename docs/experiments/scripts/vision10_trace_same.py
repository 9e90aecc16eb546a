import pickle, sys
import cv2, numpy as np
import services.vision.detector as D
cv2.setNumThreads(1)
frames = [np.array(f) for f in np.load(sys.argv[1], mmap_mode="r")[:300]]
det = D.MarkDetector()
out = []
for f in frames:
    found, tr = det.trace(f)
    cands = det.candidates(f)
    out.append(([(d.shape.value, round(d.confidence, 9), d.box) for d in found], [(t.box, t.shape, t.stage, t.scale) for t in tr], [(c.shape, c.box, c.crops.tobytes(), c.kept) for c in cands]))
pickle.dump(out, open(sys.argv[2], "wb"))
print(D.__file__, sum(len(o[1]) for o in out), sum(len(o[2]) for o in out))
