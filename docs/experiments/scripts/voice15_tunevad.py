"""Tuning data only: the tune splits' command clips in a quiet stream, and in walking noise at 20 dB:
words with no segment over them, and the spotter's accuracy, per VAD setting."""
import multiprocessing, numpy as np, sys
from services.voice.training import dataset
from services.voice.training.train import TrainConfig, TUNE_SPLITS
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from bench.ego_noise import ego_noise, mix
CFGS = {"webrtc": SegmenterConfig(vad="webrtc"), "silero": SegmenterConfig(), "silero-min0.06": SegmenterConfig(min_utterance_s=0.06)}
_E = {}
def one(r):
    if not _E: _E["e"] = make_engine("spotter")
    try: pcm = dataset.render(r)
    except Exception: return None
    if pcm is None: return None
    sp = np.frombuffer(pcm, "<i2") / 32768.0
    rng = np.random.default_rng(r.seed)
    out = {}
    for cond in ("quiet", "walk20"):
        L = int((1.2 + sp.size / SAMPLE_RATE + 1.5) * SAMPLE_RATE); at = int(1.2 * SAMPLE_RATE)
        if cond == "quiet":
            x = rng.normal(0, 3e-4, L); x[at:at + sp.size] += sp
        else:
            x = mix(sp, ego_noise(L / SAMPLE_RATE + 0.01, rng)[:L], 20.0, at)
        x = to_pcm(np.clip(x, -1, 1))
        for name, cfg in CFGS.items():
            seg = Segmenter(cfg); segs = []
            for k in range(0, len(x), 960): segs += seg.feed(x[k:k + 960])
            segs += seg.flush()
            over = [s for s in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
            ok = False
            for s in over:
                rec = _E["e"].recognise(s.pcm)
                if rec.command is not None and rec.confidence >= 0.5:
                    ok = rec.command.value == dataset.corpus.VOCABULARY[r.label]; break
            out[(cond, name)] = (bool(over), ok)
    return out
if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed) if r.label < 7]
    rows = rows[::2]
    print(len(rows), flush=True)
    with multiprocessing.Pool(2) as pool:
        res = [o for o in pool.map(one, rows, chunksize=8) if o is not None]
    for key in res[0]:
        seg = np.mean([o[key][0] for o in res]); acc = np.mean([o[key][1] for o in res])
        print(key, f"words with a segment {seg:.3f}  accuracy {acc:.3f}  (n {len(res)})")
