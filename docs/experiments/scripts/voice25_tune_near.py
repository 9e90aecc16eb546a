# Tuning-side check of round voice25 (run from the repository root: HRI_VOICE_CACHE=... .venv/bin/python THIS ARGS).
"""Tuning data only: round voice24's recipe without folds, near weight 1 vs 2; tune figures and the tune one-edit
neighbours' acceptance."""
import json, sys
from dataclasses import replace
import numpy as np
from services.voice.training import dataset, train
from services.voice.training.train import shipped_recipe, TUNE_SPLITS

if __name__ == "__main__":
    base = shipped_recipe(sizes=replace(dataset.Sizes(), neural_positives=150), split_weights=(("neural", 0.5),), word_folds=0)
    tx, ty, trows, tnames = dataset.split_rows(tuple(sp for sp in TUNE_SPLITS if sp in base.tune_splits), base.sizes, base.seed, base.workers, embedding=base.embedding, progress=False)
    tnames = np.array(tnames)
    x, y, texts, names = train.training_rows(base)
    for nw in [float(a) for a in sys.argv[1:]]:
        cfg = replace(base, near_weight=nw)
        head = train.fit(x, y, cfg, train.clip_weights(names, texts, y, cfg))
        train.fit_temperature(head, tx, ty)
        train.calibrate(head, tx, ty, cfg)
        figs = train.tune_figures(head, tx, ty)
        m = tnames == "neighbours-tune"
        p = head.probabilities(tx[m]); best = p.argmax(1)
        acc = np.mean([(b < 7) and p[i, b] >= head.accept[b] for i, b in enumerate(best)])
        print(json.dumps({"near_weight": nw, **{k: round(v, 4) for k, v in figs.items()}, "neighbours_tune_accepted": round(float(acc), 4), "n_neigh": int(m.sum())}), flush=True)
