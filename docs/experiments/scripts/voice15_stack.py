import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import GroupKFold
z = np.load("/work/scratch/w2/decprobe_tune.npz")
p, d, y, text = z["p"], z["d"], z["y"], z["text"]
n = 7
lp = np.log(np.clip(p, 1e-7, 1))
dm = d[:, :n] - d[:, n:n+1]
def curve(prob, label):
    top = prob.argmax(1); conf = prob.max(1)
    cmd = y < n
    out = []
    for target in (0.03, 0.05, 0.07, 0.10):
        ts = np.unique(conf)
        best = None
        for t in np.quantile(conf, np.linspace(0, 1, 400)):
            acc = (top != n) & (conf >= t)
            fa = acc[~cmd].mean()
            if fa <= target:
                a = (acc & (top == y))[cmd].mean()
                best = a if best is None else max(best, a)
        out.append(f"@{target:.0%}: {best:.3f}")
    print(label.ljust(28), "  ".join(out))
curve(p, "head alone")
voice = z["voice"]; groups = np.where(y < n, np.char.add("v:", voice), np.char.add("w:", text))
for name, X in [("head logp (refit)", lp), ("head + dec", np.hstack([lp, d])), ("head + dec margin", np.hstack([lp, dm, d[:, n:]])),
                ("dec alone", d)]:
    prob = np.zeros_like(p)
    for tr, te in GroupKFold(5).split(X, y, groups):
        clf = LogisticRegression(C=1.0, max_iter=2000).fit(X[tr], y[tr])
        prob[te] = clf.predict_proba(X[te])
    curve(prob, name)
