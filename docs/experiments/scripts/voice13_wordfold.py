"""Round 13 diagnostic (tuning data only): how the recipe treats near-command words it never heard.
The training negatives near the commands (hand-picked, train one-edit neighbours, two-edit words) are cut into
5 folds by word; for each fold the ensemble is fitted without that fold's words (every voice), calibrated as
`train` does on the tune splits, and scored on the fold's own training clips."""
import json, random, sys
from dataclasses import replace
import numpy as np
sys.path.insert(0, "bench")
from voice_proxy import load
from services.voice.training import corpus, dataset, train
from services.voice.training.train import TrainConfig

emb = sys.argv[1]
cfg = TrainConfig(embedding=emb, crop_width=0 if emb != "speech-embedding" else 8)
rows = load(train.training_splits(cfg.sizes), cfg)
tune = load(train.TUNE_SPLITS, cfg)
tmask = np.isin(tune.split, cfg.tune_splits)
near = sorted({w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws} | set(dataset.neighbours(cfg.sizes, cfg.seed)["train"])
              | set(dataset.two_edit(cfg.sizes)))
random.Random(0).shuffle(near)
folds = [near[k::5] for k in range(5)]
OTHER = len(corpus.VOCABULARY); GO = corpus.VOCABULARY.index("go")
tot = {"clips": 0, "accepted": 0, "go_ask": 0, "go_walk": 0}
worst_go = []
for k, words in enumerate(folds):
    out = np.isin(rows.text, words) & (rows.y == OTHER)
    flat, y, w, mean, scale = train.crop_rows(rows.x[~out], rows.y[~out], cfg)
    members = [train.fit_member(flat, y, w, cfg, cfg.seed + i) for i in range(cfg.ensemble)]
    head = train.ensemble(members, mean, scale, cfg)
    train.fit_temperature(head, tune.x[tmask], tune.y[tmask])
    report = train.calibrate(head, tune.x[tmask], tune.y[tmask], cfg)
    p = head.probabilities(rows.x[out])
    best = p.argmax(1)
    conf = np.array([head.confidence(int(b), float(p[i, b])) if b < OTHER else 0 for i, b in enumerate(best)])
    acc = (best < OTHER) & (conf >= 0.5)
    go = acc & (best == GO)
    walk = go & (conf >= 0.85)
    texts = rows.text[out]
    r = {"fold": k, "clips": int(out.sum()), "accepted": int(acc.sum()), "go_ask": int((go & ~walk).sum()),
         "go_walk": int(walk.sum()), "walk_words": sorted(set(texts[walk].tolist())),
         "go_sure": round(float(head.sure[GO]), 4), "max_go_p": round(float(p[:, GO].max()), 4),
         # the "go" sure margin (log-odds above the worst tune non-go) that no unseen word here would reach
         "margin_needed": round(float(np.log(p[:, GO].max() / (1 - p[:, GO].max()))
                                      - np.log(report["go"]["worst_other"] / (1 - report["go"]["worst_other"]))), 2)}
    print(json.dumps(r), flush=True)
    for key in tot:
        tot[key] += r[key]
print(json.dumps({"total": tot, "accepted_rate": round(tot["accepted"] / tot["clips"], 4)}))
