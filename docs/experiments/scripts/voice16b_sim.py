import pickle, numpy as np, sys
sys.path.insert(0, "/work/main")
from services.voice.training import corpus
V = corpus.VOCABULARY
res = pickle.load(open("/work/scratch/w3/tunesim.pkl", "rb"))
def decide(looks, over, c):
    ev = [(t, cmd, conf, "look") for t, cmd, conf, p in looks if c is not None and cmd is not None and conf >= c]
    ev += [(t, cmd, conf, "whole") for t, s, e, cmd, conf in over if cmd is not None and conf >= 0.5]
    if not ev: return None, None
    return min(ev)[:2]
for cond in ("quiet", "w10"):
    for c in (None, 0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95):
        acc = []; oov = []; lat = []
        for lab, _, out in res:
            looks, over = out[cond]
            t, cmd = decide(looks, over, c)
            if lab < 7:
                acc.append(cmd == V[lab])
                if cmd == V[lab]: lat.append(t)
            else:
                oov.append(cmd is not None)
        lat = np.array(lat) * 1000
        print(cond, c, f"acc {np.mean(acc):.3f} oov {np.mean(oov):.4f} ({sum(oov)}/{len(oov)}) lat p50 {np.median(lat):.0f} p90 {np.percentile(lat,90):.0f}")
