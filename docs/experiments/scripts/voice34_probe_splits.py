"""Round voice34, after its decision: the probe's candidate split by split (which splits placed the knots)."""
import json, sys, numpy as np
sys.path.insert(0, "/work/main")
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.spotter.head import Head, DEFAULT_HEAD
h = Head.load(DEFAULT_HEAD); acc = np.asarray(h.accept); n = len(h.vocabulary)
cfg = TrainConfig()
tagged = [(sp, r) for sp in ("tune", "speakers-tune", "recorded-tune", "neighbours-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
order = [t for t in tagged if t[1].label < 7][::2] + [t for t in tagged if t[1].label == 7][::2]
rows = [json.loads(l) for l in open("/tmp/voice34_probe.jsonl")]
i = 0; split = []
for row in rows:
    while (order[i][1].voice, order[i][1].text) != (row["voice"], row["text"]): i += 1
    split.append(order[i][0]); i += 1
split = np.array(split); lab = np.array([r["label"] for r in rows]); cmd = lab < 7
def dec(p):
    best = p.argmax(1); ok = best < n
    ok &= p[np.arange(len(p)), np.minimum(best, n-1)] >= acc[np.minimum(best, n-1)]
    return np.where(ok, best, -1)
po = np.array([r["1.0"] for r in rows])
g = np.exp(np.log(np.clip(np.array([[r[k] for k in ("0.95", "1.0", "1.05")] for r in rows]), 1e-6, 1)).mean(1)); g /= g.sum(1, keepdims=True)
top = po[:, :n].argmax(1); pt = po[np.arange(len(po)), top]
d0 = dec(po); border = (d0 < 0) & (pt >= 0.5 * acc[top]); d1 = np.where(border, dec(g), d0)
for sp in ("tune", "speakers-tune", "recorded-tune", "neighbours-tune"):
    m = split == sp
    c, o = cmd & m, ~cmd & m
    print(f"{sp:16} cmds {c.sum():4} heard {((d0==lab)&c).sum()} -> {((d1==lab)&c).sum()}   others {o.sum():4} taken {((d0>=0)&o).sum()} -> {((d1>=0)&o).sum()}")
