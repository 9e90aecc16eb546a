"""Tuning data only: the early look (Silero) against the 0.15 s and 0.09 s end windows, quiet and 10 dB white noise."""
import multiprocessing, sys, time
import numpy as np
sys.argv = ["x"]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from bench.voice_bench import speech_end_s

CFGS = {
    "base-0.15": (SegmenterConfig(early_quiet_s=None), False),
    "end-0.09": (SegmenterConfig(quiet_s=0.09, early_quiet_s=None), False),
    "early-0.5": (SegmenterConfig(early_quiet_s=0.09, early_confidence=0.5), True),
    "early-0.7": (SegmenterConfig(early_quiet_s=0.09, early_confidence=0.7), True),
    "early-0.85": (SegmenterConfig(early_quiet_s=0.09, early_confidence=0.85), True),
}
_E = {}

def one(r):
    if not _E:
        _E["e"] = make_engine("spotter")
    eng = _E["e"]
    try:
        pcm = dataset.render(r)
    except Exception:
        return None
    if pcm is None:
        return None
    sp = np.frombuffer(pcm, "<i2") / 32768.0
    out = {}
    for cond in ("quiet", "w10"):
        rng = np.random.default_rng(r.seed)
        L = int((1.2 + sp.size / SAMPLE_RATE + 1.5) * SAMPLE_RATE); at = int(1.2 * SAMPLE_RATE)
        if cond == "quiet":
            x = rng.normal(0, 3e-4, L)
        else:
            p = np.sqrt(np.mean(sp[np.abs(sp) > 0.02 * np.abs(sp).max()] ** 2))
            x = rng.normal(0, p / 10 ** (10 / 20), L)
        x[at:at + sp.size] += sp
        x = to_pcm(np.clip(x, -1, 1)); end = 1.2 + speech_end_s(pcm)
        for name, (cfg, early) in CFGS.items():
            seg = Segmenter(cfg, recognise=eng.recognise if early else None); segs = []
            for k in range(0, len(x), 960):
                t0 = time.perf_counter()
                got = seg.feed(x[k:k + 960])
                look = time.perf_counter() - t0
                for s in got:
                    segs.append(((k + 960) / 2 / SAMPLE_RATE, s, look))
            over = [(t, s, lk) for t, s, lk in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
            cmd = None; lat = None; taken = False
            for t, s, lk in over:
                if s.recognition is not None:
                    rec, dec, taken = s.recognition, lk, True
                else:
                    t0 = time.perf_counter(); rec = eng.recognise(s.pcm); dec = time.perf_counter() - t0
                if rec.command is not None and rec.confidence >= 0.5:
                    cmd = rec.command.value; lat = t - end + dec; break
            out[(cond, name)] = (len(over), cmd, lat, taken)
    return r.label, out

if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
    cmds = [r for r in rows if r.label < 7]; oth = [r for r in rows if r.label == 7]
    rng = np.random.default_rng(0); oth = [oth[i] for i in rng.permutation(len(oth))[:int(sys.argv[1]) if len(sys.argv) > 1 else 800]]
    print("commands", len(cmds), "others", len(oth), flush=True)
    t0 = time.time()
    with multiprocessing.Pool(2) as pool:
        res = [o for o in pool.map(one, cmds + oth, chunksize=8) if o is not None]
    print("took", round(time.time() - t0), "s")
    V = dataset.corpus.VOCABULARY
    for cond in ("quiet", "w10"):
        for key in CFGS:
            c = [(lab, o[(cond, key)]) for lab, o in res if lab < 7]; n = [o[(cond, key)] for lab, o in res if lab == 7]
            acc = np.mean([v[1] == V[lab] for lab, v in c]); oov = np.mean([v[1] is not None for v in n])
            lat = np.array([v[2] for lab, v in c if v[2] is not None and v[1] == V[lab]]) * 1000
            split = np.mean([v[0] > 1 for lab, v in c]); early = np.mean([v[3] for lab, v in c])
            print(cond, key, f"acc {acc:.3f} oov {oov:.3f} split {split:.3f} early {early:.2f} lat p50 {np.median(lat):.0f} p90 {np.percentile(lat, 90):.0f}", flush=True)
