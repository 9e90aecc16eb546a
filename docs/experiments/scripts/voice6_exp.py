"""voice6: leave-one-recorded-speaker-out proxy with the ENSEMBLE of three (not part of the repo).

    PYTHONPATH=$PWD nice -n 10 python /work/notes/runs/voice6_exp.py VARIANT ROTATION [SEED...]

VARIANT: `c8` (committed recipe: crops of 8 frames at starts 2-6) or `c6` (crops of 6 frames at starts 2-8).
ROTATION: kal16 | awb | ked: that recorded training voice (and its virtual speakers) is dropped from training
and calibration. Each member MLP (seeds 12, 13, 14 by default, exactly as `train.fit` fits them: same
standardisation, class weights, MLPClassifier settings) is fitted once and cached as float32 under
/tmp/voice6/; then the ensemble of the cached members (hidden units side by side, last layers averaged, as
`train.fit`) is scored like round 5 (`voice_exp.xhalf`: temperature + knots on one random half of the
remaining tune rows, figures on the other half, both ways). Also prints the seed-12 member alone (the
round-5 single-MLP figure, as a reproducibility check).
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, "/work/notes/runs")
import voice_exp as ve  # noqa: E402

from services.voice.spotter.head import Head  # noqa: E402
from services.voice.training import corpus, train  # noqa: E402
from services.voice.training.train import TrainConfig  # noqa: E402

OUT = Path("/tmp/voice6")
ROT = {"kal16": "flite:kal16", "awb": "flite:awb", "ked": "festival:ked"}
VARIANTS = {"c8": (8, (2, 3, 4, 5, 6)), "c6": (6, (2, 3, 4, 5, 6, 7, 8))}


def prepare(x: np.ndarray, y: np.ndarray, cfg: TrainConfig):
    flat = np.concatenate([x[:, s : s + cfg.crop_width].reshape(len(x), -1) for s in cfg.crop_starts])
    y = np.tile(y, len(cfg.crop_starts))
    flat = flat.astype(np.float32)
    mean = flat.mean(axis=0)
    scale = flat.std(axis=0) + 1e-3
    flat -= mean
    flat /= scale
    counts = np.bincount(y)
    weight = (counts.max() / counts[y]) ** cfg.balance
    return flat, y, weight / weight.mean(), mean, scale


def member(path: Path, prep, cfg: TrainConfig, seed: int):
    if path.exists():
        d = np.load(path)
        return [d["w0"], d["w1"]], [d["b0"], d["b1"]], None
    from sklearn.neural_network import MLPClassifier
    flat, y, w, _, _ = prep()
    t0 = time.time()
    clf = MLPClassifier(hidden_layer_sizes=(cfg.hidden,), alpha=cfg.alpha, max_iter=200, early_stopping=True,
                        validation_fraction=0.1, n_iter_no_change=12, random_state=seed)
    clf.fit(flat, y, sample_weight=w)
    if list(clf.classes_) != list(range(len(corpus.VOCABULARY) + 1)):
        raise RuntimeError("missing classes")
    ws = [c.astype(np.float32) for c in clf.coefs_]
    bs = [b.astype(np.float32) for b in clf.intercepts_]
    np.savez(path, w0=ws[0], w1=ws[1], b0=bs[0], b1=bs[1], n_iter=clf.n_iter_)
    return ws, bs, round(time.time() - t0)


def head_of(members, mean, scale, cfg: TrainConfig) -> Head:
    n = len(corpus.VOCABULARY)
    w0 = np.hstack([m[0][0] for m in members])
    b0 = np.concatenate([m[1][0] for m in members])
    w1 = np.vstack([m[0][1] for m in members]) / len(members)
    b1 = np.mean([m[1][1] for m in members], axis=0)
    return Head(corpus.VOCABULARY, mean, scale, [w0, w1], [b0, b1], np.full(n, 0.5), np.full(n, 0.9),
                crop_width=cfg.crop_width, crop_starts=cfg.crop_starts)


def main() -> None:
    variant, rot = sys.argv[1], sys.argv[2]
    seeds = [int(s) for s in sys.argv[3:]] or [12, 13, 14]
    d = ROT[rot]
    w, starts = VARIANTS[variant]
    cfg = replace(TrainConfig(), crop_width=w, crop_starts=starts)
    OUT.mkdir(exist_ok=True)
    t0 = time.time()
    tx, ty, tv, tn, _ = ve.load(train.TUNE_SPLITS)
    x, y, v, _, _ = ve.load(ve.TRAIN_SPLITS)
    keep = v != d
    x, y = x[keep], y[keep]
    cache: dict = {}

    def prep():
        if not cache:
            cache["p"] = prepare(x, y, cfg)
        return cache["p"]

    # mean/scale are cheap to recompute without holding the crops if every member is cached
    flat_stats = None
    members, fit_s = [], {}
    for s in seeds:
        ws, bs, secs = member(OUT / f"{variant}-{rot}-s{s}.npz", prep, cfg, s)
        members.append((ws, bs))
        fit_s[s] = secs
    if cache:
        _, _, _, mean, scale = cache["p"]
    else:
        _, _, _, mean, scale = prepare(x, y, cfg)
    del cache
    masks = {"tune": tn == "tune", "all": np.ones(len(ty), bool)}
    for r in ROT.values():
        masks[f"rec:{r}"] = (tn == "recorded-tune") & (tv == r)
    calib = tv != d
    out = {"variant": variant, "drop": d, "seeds": seeds, "fit_s": fit_s, "s": round(time.time() - t0)}
    ens = head_of(members, mean, scale, cfg)
    res = ve.xhalf(ens, tx, ty, masks, cfg, calib)
    out["ensemble"] = {"left_out": res[f"rec:{d}"], **res}
    if 12 in seeds and len(seeds) > 1:
        single = head_of([members[seeds.index(12)]], mean, scale, cfg)
        r1 = ve.xhalf(single, tx, ty, masks, cfg, calib)
        out["single12"] = {"left_out": r1[f"rec:{d}"], "tune": r1["tune"], "all": r1["all"]}
    print(json.dumps(out), flush=True)
    _ = flat_stats


if __name__ == "__main__":
    main()
