"""Round 14 exploration (tuning data only): fit the fold heads once, save their outputs for policy choices."""
import sys, json, numpy as np
sys.path.insert(0, "/work/main")
from services.voice.training import train, folds, dataset, corpus
from services.voice.training.train import TrainConfig, on_embedding
cfg = on_embedding(TrainConfig(word_folds=5), sys.argv[1])
tune_parts = [dataset.features(dataset.recipes(s, cfg.sizes, cfg.seed), cfg.workers, embedding=cfg.embedding)
              for s in train.TUNE_SPLITS if s in cfg.tune_splits]
tune = (np.concatenate([p[0] for p in tune_parts]), np.concatenate([p[1] for p in tune_parts]))
x, y, texts = train.training_rows(cfg)
other = len(corpus.VOCABULARY)
save = {}
for k, words in enumerate(folds.word_folds(folds.near_words(cfg.sizes, cfg.seed), 5)):
    out = np.isin(texts, words) & (y == other)
    head = train.fit(x[~out], y[~out], cfg)
    train.fit_temperature(head, *tune)
    chosen = train.calibrate(head, *tune, cfg)
    save[f"p{k}"] = head.probabilities(x[out]); save[f"t{k}"] = texts[out]
    save[f"tp{k}"] = head.probabilities(tune[0])
    save[f"acc{k}"] = head.accept.copy(); save[f"sure{k}"] = head.sure.copy()
    save[f"worst{k}"] = np.array([chosen[w]["worst_other"] for w in head.vocabulary])
    print(k, out.sum(), flush=True)
head = train.fit(x, y, cfg); train.fit_temperature(head, *tune); chosen = train.calibrate(head, *tune, cfg)
head.save(f"/work/scratch/w1/head14_base_{sys.argv[1]}.npz")
save["tune_y"] = tune[1]; save["tp_final"] = head.probabilities(tune[0])
np.savez(f"/work/scratch/w1/folds14_{sys.argv[1]}.npz", **save)
print("done")
