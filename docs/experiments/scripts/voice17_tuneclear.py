"""Round 17, tuning data only: the short end window (0.09 s) where the stream is clear, the whole one (0.15 s)
elsewhere. Each tune clip is placed in a stream of a training noise (pink, brown, white) at several
speech-to-noise ratios, or in the faint hiss of the benches' quiet stream, and cut twice: always with the
whole window (control) and always with the short one. Each cut records the segmenter's own SNR estimate
(`Segment.snr_db`), so any `clear_snr_db` can be replayed from one run. Writes one JSON line per clip."""
import json, multiprocessing, sys
import numpy as np
sys.argv = ["x"]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine
from services.voice.synth import noise
from bench.voice_bench import speech_end_s

SNRS = (None, 40.0, 30.0, 25.0, 20.0, 15.0, 10.0)
CFGS = {"whole": SegmenterConfig(), "short": SegmenterConfig(clear_quiet_s=0.09, clear_snr_db=-1e9)}
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
    end = 1.2 + speech_end_s(pcm)
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
        for name, cfg in CFGS.items():
            seg = Segmenter(cfg)
            segs = []
            for k in range(0, len(x), 960):
                segs += [((k + 960) / 2 / SAMPLE_RATE, s) for s in seg.feed(x[k:k + 960])]
            segs += [(len(x) / 2 / SAMPLE_RATE, s) for s in seg.flush()]
            over = [(t, s) for t, s in segs if s.start_s < 1.2 + sp.size / SAMPLE_RATE and s.end_s > 1.2]
            got, conf, lat = None, 0.0, None
            for t, s in over:
                rec = _E["e"].recognise(s.pcm)
                if rec.command is not None and rec.confidence >= 0.5:
                    got, conf, lat = rec.command.value, rec.confidence, t - end
                    break
            snrs = [s.snr_db for _, s in over if s.snr_db is not None]
            out[f"{snr}/{name}"] = {"n": len(over), "got": got, "conf": conf, "lat": lat,
                                    "snr_est": min(snrs) if snrs else None,
                                    "seg_lat": (over[0][0] - end) if over else None}
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
