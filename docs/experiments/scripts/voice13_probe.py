import sys, numpy as np
from sklearn.neural_network import MLPClassifier
from threadpoolctl import threadpool_limits
d = np.load("/work/scratch/w1/probe.npz")
e, w, y, voice, tag = d["e"].astype(np.float32), d["w"].astype(np.float32), d["y"], d["voice"], d["tag"]
OTHER = 7
feats = {
    "oww_flat": e.reshape(len(e), -1),
    "wh_meanmax": np.concatenate([w.mean(1), w.max(1)], 1),
    "wh_flat10": w.reshape(len(w), 10, 2, 384).mean(2).reshape(len(w), -1),
    "both": np.concatenate([e.reshape(len(e),-1), w.mean(1), w.max(1)],1),
    "wh_mid": w[:, 4:16].reshape(len(w), 6, 2, 384).mean(2).reshape(len(w), -1),
}
which = sys.argv[1:] or list(feats)
def run(X, tr, ev, seed=int(__import__("os").environ.get("SEED", 12))):
    mu, sd = X[tr].mean(0), X[tr].std(0) + 1e-3
    Xt, Xe = (X[tr] - mu) / sd, (X[ev] - mu) / sd
    yt = y[tr]
    c = np.bincount(yt); wt = (c.max() / c[yt]) ** 0.5
    with threadpool_limits(2, "blas"):
        clf = MLPClassifier((160,), alpha=0.1, max_iter=200, early_stopping=True, n_iter_no_change=12, random_state=seed)
        clf.fit(Xt, yt, sample_weight=wt / wt.mean())
    return clf.predict_proba(Xe)
for name in which:
    X = feats[name]
    res = []
    for spk in ("flite:kal16", "flite:awb", "festival:ked"):
        tr = np.isin(tag, ["engines", "train"]) & ~np.char.startswith(voice.astype(str), spk)
        ev = (tag == "recorded-tune") & (voice == spk)
        p = run(X, tr, ev)
        ye = y[ev]; best = p.argmax(1); cmd = ye < OTHER
        acc = np.mean(best[cmd] == ye[cmd]); fa = np.mean(best[~cmd] != OTHER)
        # at 5% non-commands accepted
        s = np.where(best < OTHER, p[np.arange(len(p)), best], 0)
        thr = np.quantile(s[~cmd], 0.95)
        acc5 = np.mean((best[cmd] == ye[cmd]) & (s[cmd] > thr))
        res.append((acc, fa, acc5))
        print(f"{name:12s} {spk:14s} acc {acc:.3f} nonc {fa:.3f} acc@5% {acc5:.3f}  (n cmd {cmd.sum()}, other {(~cmd).sum()}, train {tr.sum()})", flush=True)
    m = np.mean(res, 0)
    print(f"{name:12s} MEAN           acc {m[0]:.3f} nonc {m[1]:.3f} acc@5% {m[2]:.3f}", flush=True)
