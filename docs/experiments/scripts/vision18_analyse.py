"""Scratch: recall / false marks of baseline and baseline+proposals over thresholds, from sweep pickles."""
import sys, pickle
import numpy as np
sys.path.insert(0, '/work/main')
from schemas.messages import Shape
from services.vision.detector import box_overlap
from services.vision.verifier import CLASSES as VC, SHAPES as VS
S = (Shape.X, Shape.O, Shape.TRIANGLE)
rows = []
for f in sys.argv[1].split(','):
    rows += pickle.load(open(f, 'rb'))
def score(pt, loose, shapes=("X","O","TRIANGLE"), ov=0.3, mode='argmax'):
    tp = {s: 0 for s in S}; fp = {s: 0 for s in S}; n = {s: 0 for s in S}; fpframes = 0; added = 0
    for label, meta, found, props in rows:
        dets = [(d.shape, d.box) for d in found]
        if pt is not None:
            for shape, sc, box, pv in props:
                if sc < pt or shape.value not in shapes: continue
                if any(box_overlap(box, b) > ov for _, b in dets): continue
                k = int(np.argmax(pv[:3])) if mode == 'argmax' else VS.index(shape)
                if mode == 'none' or (VS[k] is shape and pv[k] >= loose[k]) or (mode == 'or' and sc >= 0.8):
                    dets.append((shape, box)); added += 1
        if label is not None: n[label[0]] += 1
        hit = False; wrong = False
        for s, b in dets:
            if label is not None and not hit and s == label[0] and box_overlap(b, label[1]) >= 0.5:
                hit = True; tp[s] += 1
            else:
                fp[s] += 1; wrong = True
        if label is None and wrong: fpframes += 1
    nf = sum(1 for r in rows if r[0] is None)
    return ' '.join(f"{s.value[0]} {tp[s]/(tp[s]+fp[s]+1e-9):.3f}/{tp[s]/max(1,n[s]):.3f}" for s in S) + f" miss {sum(n.values())-sum(tp.values())} fp {sum(fp.values())} (O {fp[Shape.O]}) fpframes {fpframes}/{nf} added {added}"
print('base        ', score(None, None))
for pt in (0.3, 0.4, 0.5):
    for loose in ((0.2, 0.98, 0.5), (0.5, 0.98, 0.8), (0.7, 0.99, 0.9), (0.9, 0.99, 0.95), (0.95, 0.995, 0.97)):
        print(f'pt {pt} {loose} own', score(pt, loose, mode='own'))
