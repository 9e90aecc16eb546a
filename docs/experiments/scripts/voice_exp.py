"""Tune-split experiments for the voice spotter (not part of the repo; cached features only).

    PYTHONPATH=$PWD nice -n 10 python /work/notes/runs/voice_exp.py EXP...

Figures: temperature + knots fitted on one random half of the tune rows, figures on the other half, both
ways, averaged ("xhalf"). Per-subset: tune (espeak tune voices + recorded), speakers-tune (warped),
recorded-tune per recorded voice.
"""

from __future__ import annotations

import copy
import json
import sys
import time
from dataclasses import replace

import numpy as np

from services.voice.spotter.head import Head
from services.voice.training import dataset, train
from services.voice.training.train import TrainConfig, calibrate, fit, fit_temperature, tune_figures

SEED = 12
SIZES = dataset.Sizes()
TRAIN_SPLITS = ("train", "engines", "positives", "neighbours", "speakers", "speakers:1")


def load(splits):
    xs, ys, voices, names, texts = [], [], [], [], []
    for sp in splits:
        rec = dataset.recipes(sp, SIZES, SEED)
        x, y, idx = dataset.indexed_features(rec, 2, progress=False)
        xs.append(x)
        ys.append(y)
        voices += [rec[i].voice.partition("@vtl")[0] for i in idx]
        names += [sp] * len(y)
        texts += [rec[i].text for i in idx]
    return np.concatenate(xs), np.concatenate(ys), np.array(voices), np.array(names), np.array(texts)


def xhalf(head: Head, x, y, masks: dict[str, np.ndarray], cfg: TrainConfig, calib_mask=None) -> dict:
    rng = np.random.default_rng(0)
    half = rng.random(len(y)) < 0.5
    out: dict[str, list[dict]] = {k: [] for k in masks}
    for a in (half, ~half):
        h = copy.deepcopy(head)
        cm = a if calib_mask is None else a & calib_mask
        fit_temperature(h, x[cm], y[cm])
        calibrate(h, x[cm], y[cm], cfg)
        for k, m in masks.items():
            sel = ~a & m
            if sel.sum():
                out[k].append(tune_figures(h, x[sel], y[sel]))
    res = {}
    for k, figs in out.items():
        if figs:
            res[k] = {f: round(float(np.mean([g[f] for g in figs])), 3) for f in figs[0]}
    return res


def main() -> None:
    exps = sys.argv[1:]
    tx, ty, tv, tn, _ = load(train.TUNE_SPLITS)
    masks = {"tune": tn == "tune", "tune+nb": np.isin(tn, ("tune", "neighbours-tune")),
             "speakers-tune": tn == "speakers-tune", "all": np.ones(len(ty), bool)}
    for v in ("flite:kal16", "flite:awb", "festival:ked"):
        masks[f"rec:{v}"] = (tn == "recorded-tune") & (tv == v)
    cfg0 = TrainConfig()
    for exp in exps:
        t0 = time.time()
        if exp.startswith("head:"):  # head:<path>[,norec][,go=..,stop=..,default=..]
            path, *kvs = exp[5:].split(",")
            kw = dict((kv.split("=") + [""])[:2] for kv in kvs)
            head = Head.load(path)
            cfg = cfg0
            if "default" in kw:
                cfg = replace(cfg, default_budget=float(kw["default"]))
            if "go" in kw or "stop" in kw:
                cfg = replace(cfg, budgets=(("go", float(kw.get("go", 0.003))), ("stop", float(kw.get("stop", 0.03)))))
            calib = (tn != "recorded-tune") if "norec" in kw else None
            res = xhalf(head, tx, ty, masks, cfg, calib)
            print(json.dumps({"exp": exp, **res}), flush=True)
            continue
        # exp: name[,key=value...]; keys: ensemble, alpha, hidden, balance, drop (voice left out), splits
        name, *kvs = exp.split(",")
        kw = dict((kv.split("=") + [""])[:2] for kv in kvs)
        cfg = replace(cfg0, ensemble=int(kw.get("ensemble", 1)), alpha=float(kw.get("alpha", cfg0.alpha)),
                      hidden=int(kw.get("hidden", cfg0.hidden)), balance=float(kw.get("balance", cfg0.balance)))
        splits = tuple(kw["splits"].split("+")) if "splits" in kw else TRAIN_SPLITS
        x, y, v, n, t = load(splits)
        keep = np.ones(len(y), bool)
        if "drop" in kw:
            for d in kw["drop"].split("+"):
                keep &= v != d
        if "no2edit" in kw:
            keep &= ~np.isin(t, dataset.two_edit(SIZES)) | (y < 7)
        if "nofest" in kw:  # the old recipe's voices only: no ked clips
            keep &= v != "festival:ked"
        head = fit(x[keep], y[keep], cfg)
        head.save(f"/work/notes/runs/voice-exp-{exp.replace(',', '_').replace('=', '').replace(':', '').replace('+', '-')}.npz")
        calib = None
        if "drop" in kw:  # do not calibrate on the left-out voice either
            calib = np.ones(len(ty), bool)
            for d in kw["drop"].split("+"):
                calib &= tv != d
        res = xhalf(head, tx, ty, masks, cfg, calib)
        print(json.dumps({"exp": exp, "train_rows": int(keep.sum()), "s": round(time.time() - t0), **res}), flush=True)


if __name__ == "__main__":
    main()
