"""Round 14 (tuning data only): accept-knot budgets and the go margin from word folds, scored nested (knots from four
folds applied to the fifth fold's head, on its unseen words and the tune split). Reads voice14_folds.py's output."""
import sys, numpy as np
sys.path.insert(0, "/work/main")
from services.voice.training import folds, corpus
from services.voice.spotter.head import Head
d = np.load("/work/scratch/w1/folds14_whisper-tiny.en.npz")
V = corpus.VOCABULARY; N = len(V); GO = V.index("go")
head = Head.load("/work/scratch/w1/head14_base_whisper-tiny.en.npz")
ty = d["tune_y"]
lg = lambda q: np.log(q / (1 - q)); sg = lambda z: 1 / (1 + np.exp(-z))
def conf_pub(p, acc, sure):
    best = p.argmax(1); pb = p[np.arange(len(p)), best]
    pub = np.zeros(len(p), bool); walk = np.zeros(len(p), bool)
    for c in range(N):
        m = best == c; pub[m] = pb[m] >= acc[c]; walk[m] = pb[m] >= sure[c]
    return best, pub, walk
def figures(p, y, acc, sure):
    best, pub, walk = conf_pub(p, acc, sure); cmd = y < N
    return np.mean(pub[cmd] & (best[cmd] == y[cmd])), np.mean(pub[~cmd])
def policy(ks, budgets, agg, extra):
    """shifts and go margin from folds ks"""
    sh = {}; margins = []
    for k in ks:
        p = d[f"p{k}"]; best = p.argmax(1)
        margins.append(lg(p[:, GO].max()) - lg(d[f"worst{k}"][GO]))
        for c, w in enumerate(V):
            sh.setdefault(w, []).append(folds.accept_shift(p, best, c, d[f"acc{k}"][c], budgets.get(w, budgets["_"])))
    return {w: agg(v) for w, v in sh.items()}, max(2.5, max(margins) + extra)
def apply(acc0, sure0, worst, shifts, margin):
    acc = np.array([sg(lg(acc0[c]) + shifts[w]) for c, w in enumerate(V)])
    sure = np.maximum(sure0, acc + 0.01); sure[GO] = max(sure[GO], sg(lg(worst[GO]) + margin))
    return acc, sure
for name, budgets in [("recipe", {"go": 0.003, "stop": 0.03, "_": 0.01}), ("loose", {"go": 0.005, "stop": 0.05, "_": 0.02}),
                      ("looser", {"go": 0.01, "stop": 0.05, "_": 0.03}), ("tight", {"go": 0.002, "stop": 0.02, "_": 0.005})]:
    for aggname, agg in (("max", max), ("mean", np.mean)):
        # nested: policy from 4 folds applied to the 5th fold head, scored on its unseen words and tune
        acc_u = walks = asks = 0; clips = 0; tun = []
        for k in range(5):
            ks = [j for j in range(5) if j != k]
            sh, mg = policy(ks, budgets, agg, 1.0)
            a, s = apply(d[f"acc{k}"], d[f"sure{k}"], d[f"worst{k}"], sh, mg)
            p = d[f"p{k}"]; best, pub, walk = conf_pub(p, a, s)
            acc_u += pub.sum(); clips += len(p); walks += (walk & pub & (best == GO)).sum(); asks += (pub & ~walk & (best == GO)).sum()
            tun.append(figures(d[f"tp{k}"], ty, a, s))
        sh, mg = policy(range(5), budgets, agg, 1.0)
        print(f"{name:7s} {aggname:4s} nested: unseen accepted {acc_u/clips:.3f} go walks {walks} asks {asks} | fold-head tune acc {np.mean([t[0] for t in tun]):.3f} nonc {np.mean([t[1] for t in tun]):.3f} | shifts {', '.join(f'{w} {v:.2f}' for w, v in sh.items())} margin {mg:.2f}")
# baseline: fold heads with their own tune knots
acc_u = 0; clips = 0; tun = []
for k in range(5):
    p = d[f"p{k}"]; best, pub, walk = conf_pub(p, d[f"acc{k}"], d[f"sure{k}"]); acc_u += pub.sum(); clips += len(p)
    tun.append(figures(d[f"tp{k}"], ty, d[f"acc{k}"], d[f"sure{k}"]))
print(f"baseline: unseen accepted {acc_u/clips:.3f}; tune acc {np.mean([t[0] for t in tun]):.3f} nonc {np.mean([t[1] for t in tun]):.3f}")
asks = 0
for k in range(5):
    p = d[f"p{k}"]; best, pub, walk = conf_pub(p, d[f"acc{k}"], d[f"sure{k}"]); asks += (pub & (best == GO) & ~walk).sum()
print("baseline go asks", asks)
