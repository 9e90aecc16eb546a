"""Tuning data only: record every early look (never taken) and the whole segment's result per clip, then simulate
early-look thresholds offline."""
import multiprocessing, sys, time, pickle
import numpy as np
sys.argv = sys.argv[:2]
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.audio import SAMPLE_RATE, to_pcm
from services.voice.engine import make_engine, Recognition
from bench.voice_bench import speech_end_s
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
        looks = []; k_now = [0]
        def judge(pcm_):
            rec = eng.recognise(pcm_)
            g = eng.gate; gp = g.head.probabilities(g.embedder.utterance(pcm_))[0]; gi = int(gp.argmax()); gc = g.head.classes[gi]; gconf = g.head.confidence(gi, float(gp[gi])) if gi < len(g.head.vocabulary) else 0.0
            looks.append(((k_now[0] + 960) / 2 / SAMPLE_RATE - end, rec.command.value if rec.command else None, rec.confidence, (gc, gconf)))
            return Recognition(None, "x", 0.0, "t")
        seg = Segmenter(SegmenterConfig(early_quiet_s=0.09), recognise=judge); segs = []
        for k in range(0, len(x), 960):
            k_now[0] = k
            for s in seg.feed(x[k:k + 960]):
                rec = eng.recognise(s.pcm)
                segs.append(((k + 960) / 2 / SAMPLE_RATE - end, s.start_s, s.end_s, rec.command.value if rec.command else None, rec.confidence))
        over = [s for s in segs if s[1] < 1.2 + sp.size / SAMPLE_RATE and s[2] > 1.2]
        out[cond] = (looks, over)
    return r.label, r.text if hasattr(r, "text") else None, out

if __name__ == "__main__":
    cfg = TrainConfig()
    rows = [r for sp in ("tune", "speakers-tune", "recorded-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
    cmds = [r for r in rows if r.label < 7]; oth = [r for r in rows if r.label == 7]
    rng = np.random.default_rng(0); oth = [oth[i] for i in rng.permutation(len(oth))[:800]]
    t0 = time.time()
    with multiprocessing.Pool(2) as pool:
        res = [o for o in pool.map(one, cmds + oth, chunksize=8) if o is not None]
    pickle.dump(res, open("/work/scratch/w3/tunesim2.pkl", "wb"))
    print("took", round(time.time() - t0), "s", len(res))
