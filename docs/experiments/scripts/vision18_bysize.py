import sys, pickle, collections
import numpy as np
sys.path.insert(0, '/work/main')
from services.vision.detector import box_overlap
from services.vision.verifier import SHAPES as VS
rows = []
for f in sys.argv[1].split(','): rows += pickle.load(open(f, 'rb'))
pt, loose = 0.3, (0.3, 0.9, 0.7)
for key in ('size_px', 'blur_px', 'finger_near_mark', 'tilt_deg'):
    c = collections.defaultdict(lambda: [0, 0, 0, 0])
    for label, meta, found, props in rows:
        if label is None: continue
        b = meta[key]
        base = any(d.shape == label[0] and box_overlap(d.box, label[1]) >= 0.5 for d in found)
        pr = any(s == label[0] and sc >= pt and box_overlap(bx, label[1]) >= 0.5 for s, sc, bx, pv in props)
        ver = any(s == label[0] and sc >= pt and box_overlap(bx, label[1]) >= 0.5 and pv[VS.index(s)] >= loose[VS.index(s)] for s, sc, bx, pv in props)
        c[b][0] += 1; c[b][1] += base; c[b][2] += pr; c[b][3] += base or ver
    print(key, {k: (v[0], round(v[1]/v[0], 3), round(v[2]/v[0], 3), round(v[3]/v[0], 3)) for k, v in sorted(c.items())})
