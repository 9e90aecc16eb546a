"""Tuning data only: Silero's speech threshold, tune clips in a stream of the training noises (pink, brown) at 20 and 10 dB."""
import multiprocessing, numpy as np, sys
sys.argv = ["x"]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from services.voice.synth import noise
from services.voice.vad import SileroEndpointer
import services.voice.segmenter as segmod
THRS = (0.5, 0.4, 0.3)
_E = {}
def one(r):
    if not _E: _E["e"] = make_engine("spotter")
    try: pcm = dataset.render(r)
    except Exception: return None
    if pcm is None: return None
    sp = np.frombuffer(pcm, "<i2") / 32768.0
    rng = np.random.default_rng(r.seed)
    out = {}
    for snr in (20.0, 10.0):
        L = int((1.2 + sp.size / SAMPLE_RATE + 1.5) * SAMPLE_RATE); at = int(1.2 * SAMPLE_RATE)
        z = noise(str(rng.choice(["pink", "brown"])), L, rng)
        active = sp[np.abs(sp) > 0.05 * np.abs(sp).max()]
        x = z * np.sqrt(np.mean(active ** 2) / 10 ** (snr / 10)); x[at:at + sp.size] += sp
        x = to_pcm(np.clip(x, -1, 1))
        for thr in THRS:
            seg = Segmenter(SegmenterConfig()); seg._ep = SileroEndpointer(threshold=thr)
            segs = []
            for k in range(0, len(x), 960): segs += seg.feed(x[k:k + 960])
            segs += seg.flush()
            over = [s for s in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
            got = None
            for s in over:
                rec = _E["e"].recognise(s.pcm)
                if rec.command is not None and rec.confidence >= 0.5: got = rec.command.value; break
            out[(snr, thr)] = (bool(over), got)
    return r.label, out
if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)][::2]
    with multiprocessing.Pool(2) as pool:
        res = [o for o in pool.map(one, rows, chunksize=8) if o is not None]
    V = dataset.corpus.VOCABULARY
    for snr in (20.0, 10.0):
        for thr in THRS:
            cmd = [(o[(snr, thr)]) for lab, o in res if lab < 7]; labs = [lab for lab, o in res if lab < 7]
            oth = [o[(snr, thr)] for lab, o in res if lab == 7]
            acc = np.mean([g == V[l] for (seg, g), l in zip(cmd, labs)]); noseg = np.mean([not s for s, g in cmd])
            fa = np.mean([g is not None for s, g in oth])
            print(f"{snr:.0f} dB thr {thr}: commands {acc:.3f} (no segment {noseg:.3f}, n {len(cmd)})  others accepted {fa:.3f} (n {len(oth)})", flush=True)
