"""Tuning data only: Silero's end window (quiet 30 ms frames before a word ends) against latency, splits, accuracy."""
import multiprocessing, numpy as np, sys
sys.argv = ["x"]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from bench.voice_bench import speech_end_s
CFGS = {f"silero-{w}": SegmenterConfig(window_s=w) for w in (0.06, 0.09, 0.15)}
_E = {}
def one(r):
    if not _E: _E["e"] = make_engine("spotter")
    try: pcm = dataset.render(r)
    except Exception: return None
    if pcm is None: return None
    sp = np.frombuffer(pcm, "<i2") / 32768.0
    rng = np.random.default_rng(r.seed)
    L = int((1.2 + sp.size / SAMPLE_RATE + 1.5) * SAMPLE_RATE); at = int(1.2 * SAMPLE_RATE)
    x = rng.normal(0, 3e-4, L); x[at:at + sp.size] += sp
    x = to_pcm(np.clip(x, -1, 1)); end = 1.2 + speech_end_s(pcm)
    out = {}
    for name, cfg in CFGS.items():
        seg = Segmenter(cfg); segs = []
        for k in range(0, len(x), 960):
            for s in seg.feed(x[k:k + 960]): segs.append(((k + 960) / 2 / SAMPLE_RATE, s))
        over = [(t, s) for t, s in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
        ok = False; lat = None
        for t, s in over:
            rec = _E["e"].recognise(s.pcm)
            if rec.command is not None and rec.confidence >= 0.5:
                ok = rec.command.value == dataset.corpus.VOCABULARY[r.label]; lat = t - end; break
        out[name] = (len(over), ok, lat if lat is not None else (over[0][0] - end if over else None))
    return out
if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed) if r.label < 7]
    with multiprocessing.Pool(1) as pool:
        res = [o for o in pool.map(one, rows, chunksize=8) if o is not None]
    for key in CFGS:
        n_over = np.array([o[key][0] for o in res]); acc = np.mean([o[key][1] for o in res])
        lat = np.array([o[key][2] for o in res if o[key][2] is not None]) * 1000
        print(key, f"n {len(res)} acc {acc:.3f} no segment {np.mean(n_over == 0):.3f} split {np.mean(n_over > 1):.3f} "
              f"latency p50 {np.median(lat):.0f} p90 {np.percentile(lat, 90):.0f} ms", flush=True)
