"""Tune-only probe: test-time warps (resampled copies, speed+pitch like another vocal tract) averaged at decode."""
import json, multiprocessing, sys
import numpy as np
sys.argv = sys.argv[:1]
sys.path.insert(0, "/work/main")
from scipy.signal import resample_poly
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.spotter.head import Head, DEFAULT_HEAD
from services.voice.spotter.embedders import embedder_for
from services.voice.audio import to_pcm

FACTORS = {1.0: (1, 1), 0.9: (10, 9), 0.95: (20, 19), 1.05: (20, 21), 1.1: (10, 11)}  # speed s: up/down
_S = {}

def one(r):
    if not _S:
        h = Head.load(DEFAULT_HEAD); _S["h"] = h; _S["e"] = embedder_for(h.embedding)
    try:
        pcm = dataset.render(r)
    except Exception:
        return None
    if pcm is None:
        return None
    x = np.frombuffer(pcm, "<i2") / 32768.0
    out = {"label": r.label, "voice": r.voice, "text": r.text}
    for s, (up, down) in FACTORS.items():
        y = x if s == 1.0 else resample_poly(x, up, down)
        p = _S["h"].probabilities(_S["e"].utterance(to_pcm(np.clip(y, -1, 1))))[0]
        out[str(s)] = [round(float(v), 5) for v in p]
    return out

if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune", "neighbours-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
    cmds = [r for r in rows if r.label < 7][::2]
    others = [r for r in rows if r.label == 7][::2]
    print(len(cmds), len(others), file=sys.stderr)
    with multiprocessing.get_context("spawn").Pool(2) as pool, open("/tmp/voice34_probe.jsonl", "w") as f:
        for o in pool.imap(one, cmds + others, chunksize=8):
            if o is not None:
                f.write(json.dumps(o) + "\n"); f.flush()
