# Tuning-side check of round voice25 (run from the repository root: HRI_VOICE_CACHE=... .venv/bin/python THIS ARGS).
"""Tuning data only: recipes without folds; tune figures and the tune one-edit neighbours' acceptance.
args: NAME=neural,pseudo ... (neural clips per command at weight 0.5 if > 0; pseudo repeats)"""
import json, sys
from dataclasses import replace
import numpy as np
from services.voice.training import dataset, train
from services.voice.training.train import shipped_recipe, TUNE_SPLITS

if __name__ == "__main__":
    for arg in sys.argv[1:]:
        name, _, spec = arg.partition("=")
        neural, pseudo = (int(v) for v in spec.split(","))
        sizes = replace(shipped_recipe().sizes, neural_positives=neural, pseudo_repeats=pseudo)
        cfg = shipped_recipe(sizes=sizes, word_folds=0, split_weights=(("neural", 0.5),) if neural else ())
        tx, ty, trows, tnames = dataset.split_rows(tuple(sp for sp in TUNE_SPLITS if sp in cfg.tune_splits), cfg.sizes, cfg.seed, cfg.workers, embedding=cfg.embedding, progress=False)
        tnames = np.array(tnames)
        x, y, texts, names = train.training_rows(cfg)
        head = train.fit(x, y, cfg, train.clip_weights(names, texts, y, cfg))
        train.fit_temperature(head, tx, ty)
        train.calibrate(head, tx, ty, cfg)
        figs = train.tune_figures(head, tx, ty)
        out = {"name": name, "train_clips": len(y), **{k: round(v, 4) for k, v in figs.items()}}
        for split in ("neighbours-tune", "tune", "speakers-tune"):
            m = tnames == split
            p = head.probabilities(tx[m]); best = p.argmax(1)
            pub = np.array([(b < 7) and p[i, b] >= head.accept[b] for i, b in enumerate(best)])
            other = ty[m] == 7
            out[f"{split}_other_accepted"] = round(float(pub[other].mean()), 4)
            if (~other).any():
                out[f"{split}_cmd_acc"] = round(float(np.mean(pub[~other] & (best[~other] == ty[m][~other]))), 4)
        print(json.dumps(out), flush=True)
