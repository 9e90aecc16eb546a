"""voice7: mel-level variants on the leave-one-recorded-speaker-out proxy (not part of the repo).

    PYTHONPATH=$PWD nice -n 10 python /work/notes/runs/voice7_exp.py VARIANT EVERY [ROTATION...]

Rows: every tune-split row (train.TUNE_SPLITS, full) and the fixed subset recipes[::EVERY] of each training split
(voice_exp.TRAIN_SPLITS); mels from the round-6 cache (`dataset.indexed_mels`), embedded here with
`Embedder.embed_mel(...)[:FRAMES]` (batched).
VARIANT: base (mels unchanged) | cmvn (per-utterance mean over speech frames removed per band, the espeak-ng training
rows' global mean added back; applied to every row, train and tune) | fmask (each training clip once more
with one random band of 2-6 bins set to its utterance mean, seed 7, as extra training rows) | tilt (each
training clip once more with a random spectral tilt, seed 7, as extra rows) | dup (control: every training
row twice, unchanged).
Per rotation: that recorded voice (and its virtual speakers) out of training and calibration; one MLP (seed 12,
committed recipe otherwise: train.fit with ensemble=1); voice_exp.xhalf exactly as rounds 5 and 6."""
from __future__ import annotations

import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, "/work/notes/runs")
import voice_exp as ve  # noqa: E402

from services.voice.spotter.features import EMBED_DIM, FRAMES, MEL_STEP, MEL_WINDOW, Embedder  # noqa: E402
from services.voice.training import dataset, train  # noqa: E402
from services.voice.training.train import TrainConfig  # noqa: E402

OUT = Path("/tmp/voice7")
ROT = ("flite:kal16", "flite:awb", "festival:ked")
_E: Embedder | None = None


USED = range(2, 14)
"""Embedding frames any crop of the committed recipe reads (crops of 8 at starts 2-6); the others are left NaN
(so that any use of them would show) to save a quarter of the embedding pass."""


def embed(mel: np.ndarray) -> np.ndarray:
    """(n, mel frames, 32) -> (n, FRAMES, 96) float16, as Embedder.embed_mel(m)[:FRAMES] per clip (frames USED)."""
    global _E
    if _E is None:
        _E = Embedder(threads=1)
    starts = list(range(0, mel.shape[1] - MEL_WINDOW + 1, MEL_STEP))[:FRAMES]
    starts = [starts[k] for k in USED]
    out = np.full((len(mel), FRAMES, EMBED_DIM), np.nan, np.float16)
    b = 32
    for i in range(0, len(mel), b):
        chunk = mel[i : i + b].astype(np.float32)
        win = np.stack([chunk[:, s : s + MEL_WINDOW] for s in starts], axis=1)
        r = _E._emb.run(None, {"input_1": win.reshape(-1, MEL_WINDOW, mel.shape[2], 1)})[0]
        out[i : i + b, USED.start : USED.stop] = r.reshape(len(chunk), len(starts), EMBED_DIM)
    return out


def pad_level(mel: np.ndarray) -> float:
    """Energy (mean over bands) of the quiet padding noise `centre` puts around every utterance."""
    return float(np.median(mel[:, :3].astype(np.float32).mean(axis=2)))


def masks_of(mel: np.ndarray, pad: float) -> tuple[np.ndarray, np.ndarray]:
    """(utterance frames: energy > the clip's padding level + 0.3 (`pad` unused), speech frames: utterance frames above the utterance's median
    energy), each (n, frames) bool."""
    e = mel.astype(np.float32).mean(axis=2)
    floor = np.median(e[:, :5], axis=1)  # the clip's padding (at least 15 frames each side; its level varies a little)
    utt = e > floor[:, None] + 0.3
    utt[~utt.any(axis=1)] = True
    med = np.array([np.median(e[i][utt[i]]) for i in range(len(e))])
    speech = utt & (e >= med[:, None])
    return utt, speech


def band_means(mel: np.ndarray, m: np.ndarray) -> np.ndarray:
    w = m[..., None].astype(np.float32)
    return (mel.astype(np.float32) * w).sum(axis=1) / w.sum(axis=1)


def load(splits, every: int, variant: str, pad: float | None, g: np.ndarray | None):
    xs, ys, vs, ns, checks = [], [], [], [], []
    for sp in splits:
        rec = dataset.recipes(sp, ve.SIZES, ve.SEED)
        if every > 1 and sp in ve.TRAIN_SPLITS:
            rec = rec[::every]
        key = dataset._key(rec)
        mel, y, idx = dataset.indexed_mels(rec, 2, progress=False)
        voices = np.array([rec[i].voice.partition("@vtl")[0] for i in idx])
        path = OUT / f"feat-{variant}-{key}.npz"
        if path.exists():
            d = np.load(path)
            x, xy, xv = d["x"], d["y"], d["v"]
        else:
            if variant == "base":
                x = embed(mel)
                f, _, fidx = dataset.indexed_features(rec, 2, progress=False)
                assert (fidx == idx).all()
                diff = np.abs(x[:, USED.start : USED.stop].astype(np.float32) - f[:, USED.start : USED.stop].astype(np.float32))
                checks.append({"split": sp, "max_abs_diff": float(diff.max()), "mean_abs_diff": float(diff.mean()),
                               "feat_abs_mean": float(np.abs(f.astype(np.float32)).mean())})
                xy, xv = y, voices
            elif variant == "cmvn":
                _, speech = masks_of(mel, pad)
                mu = band_means(mel, speech)
                x = embed(mel.astype(np.float32) - (mu - g)[:, None, :])
                xy, xv = y, voices
            elif variant == "dup":  # control for fmask / tilt: every training row twice, unchanged
                if sp not in ve.TRAIN_SPLITS:
                    x, xy, xv = load([sp], every, "base", pad, g)[:3]
                else:
                    base = load([sp], every, "base", pad, g)[0]
                    x, xy, xv = np.concatenate([base, base]), np.concatenate([y, y]), np.concatenate([voices, voices])
            elif variant in ("fmask", "tilt"):
                if sp not in ve.TRAIN_SPLITS:
                    x, xy, xv = load([sp], every, "base", pad, g)[:3]
                else:
                    rng = np.random.default_rng([7, len(sp), sum(map(ord, sp))])
                    utt, _ = masks_of(mel, pad)
                    aug = mel.astype(np.float32)
                    nb = mel.shape[2]
                    if variant == "fmask":
                        mu = band_means(mel, utt)
                        for i in range(len(aug)):
                            w = int(rng.integers(2, 7))
                            f0 = int(rng.integers(0, nb - w + 1))
                            rows = np.where(utt[i])[0]
                            aug[i][np.ix_(rows, np.arange(f0, f0 + w))] = mu[i, f0 : f0 + w]
                    else:
                        ramp = np.linspace(-0.5, 0.5, nb, dtype=np.float32)
                        t = rng.uniform(-1.0, 1.0, len(aug)).astype(np.float32)
                        aug += (utt[..., None] * (t[:, None, None] * ramp[None, None, :])).astype(np.float32)
                    base = load([sp], every, "base", pad, g)[0]
                    x = np.concatenate([base, embed(aug)])
                    xy, xv = np.concatenate([y, y]), np.concatenate([voices, voices])
            else:
                raise ValueError(variant)
            np.savez(path, x=x, y=xy, v=xv)
        xs.append(x)
        ys.append(xy)
        vs.append(xv)
        ns += [sp] * len(xy)
        if checks:
            print(json.dumps({"check": checks[-1]}), flush=True)
            checks = []
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(vs), np.array(ns)


def globals_of(every: int) -> tuple[float, np.ndarray]:
    """Padding level (from the tune rows) and the training rows' global mean speech spectrum per band (mean of
    the utterances' speech-frame means over the subset's espeak-ng training rows, real and virtual speakers:
    no rotation leaves them out, so one G serves all three without any left-out speaker in it)."""
    path = OUT / f"global-{every}.npz"
    if path.exists():
        d = np.load(path)
        return float(d["pad"]), d["g"]
    mel, _, _ = dataset.indexed_mels(dataset.recipes("tune", ve.SIZES, ve.SEED), 2, progress=False)
    pad = pad_level(mel)
    mus = []
    for sp in ve.TRAIN_SPLITS:
        rec = dataset.recipes(sp, ve.SIZES, ve.SEED)
        if every > 1:
            rec = rec[::every]
        m, _, idx = dataset.indexed_mels(rec, 2, progress=False)
        espeak = np.array([rec[i].voice.startswith("espeak:") for i in idx])  # never a left-out voice
        mus.append(band_means(m[espeak], masks_of(m[espeak], pad)[1]))
    g = np.concatenate(mus).mean(axis=0)
    np.savez(path, pad=pad, g=g)
    return pad, g


def main() -> None:
    variant, every = sys.argv[1], int(sys.argv[2])
    rots = sys.argv[3:] or ROT
    OUT.mkdir(exist_ok=True)
    pad, g = globals_of(every)
    t0 = time.time()
    tx, ty, tv, tn = load(train.TUNE_SPLITS, every, variant, pad, g)
    x, y, v, _ = load(ve.TRAIN_SPLITS, every, variant, pad, g)
    print(json.dumps({"variant": variant, "every": every, "train_rows": len(y), "tune_rows": len(ty),
                      "embed_s": round(time.time() - t0)}), flush=True)
    cfg = replace(TrainConfig(), ensemble=1)
    for d in rots:
        t1 = time.time()
        keep = v != d
        head = train.fit(x[keep], y[keep], cfg)
        head.save(OUT / f"head-{variant}-{every}-{d.replace(':', '_')}.npz")
        masks = {"tune": tn == "tune", "all": np.ones(len(ty), bool)}
        for r in ROT:
            masks[f"rec:{r}"] = (tn == "recorded-tune") & (tv == r)
        res = ve.xhalf(head, tx, ty, masks, cfg, tv != d)
        print(json.dumps({"variant": variant, "every": every, "drop": d, "train_rows": int(keep.sum()),
                          "s": round(time.time() - t1), "left_out": res[f"rec:{d}"], **res}), flush=True)


if __name__ == "__main__":
    main()
