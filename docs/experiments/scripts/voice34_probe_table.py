import json, sys, numpy as np
sys.path.insert(0, "/work/main")
from services.voice.spotter.head import Head, DEFAULT_HEAD
h = Head.load(DEFAULT_HEAD); acc = np.asarray(h.accept, float); n = len(h.vocabulary)
rows = [json.loads(l) for l in open(sys.argv[1] if len(sys.argv) > 1 else "/tmp/voice34_probe.jsonl")]
lab = np.array([r["label"] for r in rows]); cmd = lab < 7
def P(keys, geo=False):
    a = np.array([[r[k] for k in keys] for r in rows])  # N x K x C
    if geo:
        g = np.exp(np.log(np.clip(a, 1e-6, 1)).mean(1)); return g / g.sum(1, keepdims=True)
    return a.mean(1)
VARS = {"orig": P(["1.0"]), "mean3": P(["0.95", "1.0", "1.05"]), "mean5": P(["0.9", "0.95", "1.0", "1.05", "1.1"]),
        "geo3": P(["0.95", "1.0", "1.05"], True), "geo5": P(["0.9", "0.95", "1.0", "1.05", "1.1"], True),
        "only0.95": P(["0.95"]), "only1.05": P(["1.05"])}
def score(p, m, mask=None):
    mask = np.ones(len(p), bool) if mask is None else mask
    best = p.argmax(1); ok = (best < n)
    thr = np.minimum(acc * m, 0.999)
    ok &= p[np.arange(len(p)), np.minimum(best, n - 1)] >= thr[np.minimum(best, n - 1)]
    a = ((best == lab) & ok & cmd & mask).sum() / (cmd & mask).sum()
    o = (ok & ~cmd & mask).sum() / (~cmd & mask).sum()
    return a, o
ms = np.linspace(0.3, 2.5, 300)
print("clips", len(rows), "commands", cmd.sum(), "others", (~cmd).sum())
for name, p in VARS.items():
    a1, o1 = score(p, 1.0)
    curve = sorted((score(p, m)[1], score(p, m)[0]) for m in ms)
    oo = np.array([c[0] for c in curve]); aa = np.array([c[1] for c in curve])
    at = [max(aa[oo <= t]) if (oo <= t).any() else float('nan') for t in (0.03, 0.05, 0.08, 0.10)]
    print(f"{name:9} at knots: acc {a1:.3f} other {o1:.3f} | best acc with other<=3/5/8/10%: " + " ".join(f"{x:.3f}" for x in at))
print("--- flips at the knots, geo3 vs orig; by voice engine")
def dec(p):
    best = p.argmax(1); ok = best < n
    ok &= p[np.arange(len(p)), np.minimum(best, n-1)] >= acc[np.minimum(best, n-1)]
    return np.where(ok, best, -1)
d0, d1 = dec(VARS["orig"]), dec(VARS["geo3"]); d5 = dec(VARS["geo5"])
right0, right1, right5 = (d0 == lab) & cmd, (d1 == lab) & cmd, (d5 == lab) & cmd
fa0, fa1, fa5 = (d0 >= 0) & ~cmd, (d1 >= 0) & ~cmd, (d5 >= 0) & ~cmd
print("commands gained/lost geo3", (right1 & ~right0).sum(), (right0 & ~right1).sum(), " geo5", (right5 & ~right0).sum(), (right0 & ~right5).sum())
print("others newly accepted/removed geo3", (fa1 & ~fa0).sum(), (fa0 & ~fa1).sum(), " geo5", (fa5 & ~fa0).sum(), (fa0 & ~fa5).sum())
eng = np.array([r["voice"].split(":")[0] + (":vtl" if "@vtl" in r["voice"] else "") for r in rows])
for e in sorted(set(eng)):
    m = eng == e
    print(f"{e:14} cmds {(cmd&m).sum():4} acc {right0[m].sum()/max(1,(cmd&m).sum()):.3f}->{right1[m].sum()/max(1,(cmd&m).sum()):.3f}  others {(~cmd&m).sum():4} acc'd {fa0[m].sum()}->{fa1[m].sum()}")
print("removed others:", sorted(r["text"] for r, a, b in zip(rows, fa0, fa1) if a and not b))
print("added others:", sorted(r["text"] for r, a, b in zip(rows, fa0, fa1) if b and not a))
print("--- geo3 only where the original is borderline")
sure = np.asarray(h.sure, float)
po = VARS["orig"]; top = po[:, :n].argmax(1); pt = po[np.arange(len(po)), top]
for lo, hi_ in ((0.5, 1.0), (0.3, 1.0), (0.5, 0.0), (0.3, 0.0), (0.0, 0.0)):
    # borderline: top command prob between lo*accept and sure (hi_=1) or between lo*accept and accept (hi_=0: rejected only)
    upper = sure[top] if hi_ else acc[top]
    border = (pt >= lo * acc[top]) & (pt < upper)
    mix = np.where(border[:, None], VARS["geo3"], po)
    d = dec(mix); r = (d == lab) & cmd; f = (d >= 0) & ~cmd
    print(f"lo {lo} {'to sure' if hi_ else 'to accept'}: looked again {border.mean():.2f} (cmds {border[cmd].mean():.2f}, others {border[~cmd].mean():.2f}); acc {r.sum()/cmd.sum():.3f} other {f.sum()/(~cmd).sum():.3f}")
print("--- rescue variants (lo 0.5, rejected only)")
upper = acc[top]; border = (pt >= 0.5 * acc[top]) & (pt < upper) & (po.argmax(1) <= n)
d_orig = dec(po)
for name in ("geo3", "geo5", "mean3", "mean5", "only0.95", "only1.05"):
    d2 = dec(VARS[name]); d = np.where(border & (d_orig < 0), d2, d_orig)
    r = (d == lab) & cmd; f = (d >= 0) & ~cmd
    wrong = (d >= 0) & cmd & (d != lab)
    print(f"{name:9} acc {r.sum()/cmd.sum():.3f} (+{(r & (d_orig != lab)).sum()}) other {f.sum()}/{(~cmd).sum()} (+{(f & (d_orig < 0)).sum()}) wrong-command {wrong.sum()} (orig {((d_orig>=0)&cmd&(d_orig!=lab)).sum()})")
    if name == "geo3":
        gained = [(rows[i]["voice"], rows[i]["text"]) for i in np.where(r & (d_orig != lab))[0]]
        print("  gained by word:", sorted(__import__('collections').Counter(t for _, t in gained).items()))
        print("  added others:", [rows[i]["text"] + "->" + h.vocabulary[d[i]] for i in np.where(f & (d_orig < 0))[0]])
sup = (po.argmax(1) == n) & (pt >= acc[top])
print("superset cases:", sup.sum(), "of which geo3 accepts:", (dec(VARS["geo3"])[sup] >= 0).sum())
