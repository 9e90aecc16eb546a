import pickle, numpy as np, sys
sys.path.insert(0, "/work/main")
from services.voice.training import corpus
V = corpus.VOCABULARY
res = pickle.load(open("/work/scratch/w3/tunesim2.pkl", "rb"))
def decide(looks, over, c, agree, gmin):
    ev = []
    for t, cmd, conf, (gc, gconf) in looks:
        if c is None or cmd is None or conf < c: continue
        if agree and not (gc == cmd and gconf >= gmin): continue
        ev.append((t, cmd))
    ev += [(t, cmd) for t, s, e, cmd, conf in over if cmd is not None and conf >= 0.5]
    return min(ev) if ev else (None, None)
for cond in ("quiet", "w10"):
    for c, agree, gmin in ((None, False, 0), (0.7, False, 0), (0.85, False, 0), (0.5, True, 0.5), (0.6, True, 0.5), (0.7, True, 0.5), (0.7, True, 0.7), (0.8, True, 0.5)):
        acc = []; oov = []; lat = []
        for lab, _, out in res:
            looks, over = out[cond]
            t, cmd = decide(looks, over, c, agree, gmin)
            if lab < 7:
                acc.append(cmd == V[lab])
                if cmd == V[lab]: lat.append(t)
            else:
                oov.append(cmd is not None)
        lat = np.array(lat) * 1000
        print(cond, c, "agree" if agree else "", gmin, f"acc {np.mean(acc):.3f} oov {sum(oov)}/{len(oov)} lat p50 {np.median(lat):.0f} p90 {np.percentile(lat,90):.0f}")
