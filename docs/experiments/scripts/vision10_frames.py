"""Cache tuning-generator frames (and, separately, held-out frames for the final timing only)."""
import sys
import numpy as np
sys.path.insert(0, "/work/main/bench")
from vision_bench import _generator, CLASSES

split, seed, n, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
f = _generator(split, seed)
imgs = []
for i in range(n):
    img, _, _ = f(CLASSES[i % len(CLASSES)])
    imgs.append(img)
np.save(out, np.stack(imgs))
