"""Round 18, tuning data only: Silero's start threshold lowered with its end threshold kept (round 15d lowered
both, and its words ran into the noise). Each tune clip in the benches' faint hiss and in pink, brown or white
noise at 20 and 10 dB, cut with each (start, end) pair; one JSON line per clip."""
import json, multiprocessing, sys
import numpy as np
sys.argv = ["x"]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from services.voice.synth import noise

SNRS = (None, 20.0, 10.0)
PAIRS = ((0.5, 0.35), (0.45, 0.35), (0.4, 0.35), (0.35, 0.3), (0.4, 0.25))
_E = {}


def one(r):
    if not _E:
        _E["e"] = make_engine("spotter")
    try:
        pcm = dataset.render(r)
    except Exception:
        return None
    if pcm is None:
        return None
    sp = np.frombuffer(pcm, "<i2") / 32768.0
    rng = np.random.default_rng(r.seed)
    at = int(1.2 * SAMPLE_RATE)
    L = at + sp.size + int(1.5 * SAMPLE_RATE)
    active = sp[np.abs(sp) > 0.05 * np.abs(sp).max()]
    out = {"label": r.label, "seed": r.seed}
    for snr in SNRS:
        if snr is None:
            x = rng.normal(0, 3e-4, L)
        else:
            z = noise(str(rng.choice(["pink", "brown", "white"])), L, rng)
            x = z * np.sqrt(np.mean(active ** 2) / np.mean(z ** 2) / 10 ** (snr / 10))
        x[at:at + sp.size] += sp
        x = to_pcm(np.clip(x, -1, 1))
        for start, end in PAIRS:
            seg = Segmenter(SegmenterConfig(threshold=start, end_threshold=end))
            segs = []
            for k in range(0, len(x), 960):
                segs += seg.feed(x[k:k + 960])
            segs += seg.flush()
            over = [s for s in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
            got = None
            for s in over:
                rec = _E["e"].recognise(s.pcm)
                if rec.command is not None and rec.confidence >= 0.5:
                    got = rec.command.value
                    break
            out[f"{snr}/{start}/{end}"] = {"n": len(over), "got": got, "len": [round(s.end_s - s.start_s, 2) for s in over],
                                          "all": len(segs)}
    return out


if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
    cmds = [r for r in rows if r.label < 7][::2]
    others = [r for r in rows if r.label == 7][::4]
    with multiprocessing.Pool(2) as pool, open(sys.stdout.fileno(), "w", closefd=False) as f:
        for o in pool.imap(one, cmds + others, chunksize=8):
            if o is not None:
                f.write(json.dumps(o) + "\n")
                f.flush()
