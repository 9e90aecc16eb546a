"""voice9: an honest tuning proxy for enrolment (not part of the repo).

    PYTHONPATH=$PWD nice -n 10 python /work/notes/runs/voice9_enrol.py RECIPE...

For each recorded training speaker d (flite kal16, flite awb, Festival ked): the leave-d-out ensemble of three
(voice8's cached members /tmp/voice8/base-<rot>-s12/13/14.npz, exactly train.fit's MLPs fitted without d and its
virtual speakers; ensemble by voice6_exp.head_of), its temperature and knots fitted as `train` does (on the
`tune`, `neighbours-tune` and `speakers-tune` rows, here without d and d's virtual speakers; full rows, no halves:
d's clips are never in the calibration), then enrolled (services.voice.enrol.adapt) on 5 fresh samples per command
by d (speed and pitch x0.9-1.1, 3 clean + 2 augmented, seeds 50_000+, not the scoring clips' seeds), and scored on
d's `recorded-tune` clips (210 commands, OOV_TUNE x3 + the tune one-edit neighbours x1), through the service's
decision (SpotterEngine.recognise from features: the enrolled "go" capped below 0.85 unless the calibrated head
is sure) and the bench's reasoner policy (go >= 0.85 walks, 0.5-0.85 asks).

RECIPE: name[,key=value...]; keys: prior, steps, copies, rev (reversed_others), others (0/1: the user also says
the prompt list enrol.PROMPT_OTHERS-by-rule, once each, clean), knots (0/1: re-place accept knots after
adaptation), anchors (0/1), offset (2: the next two words per command by the same rule), reps (2: the prompt
list said twice), both (1: the list and the next one), ow (weight of the "other" class; needs the uncommitted
EnrolConfig.other_weight of round 2: weight *= ow for "other" rows after balancing).
"""
from __future__ import annotations

import hashlib
import json
import pickle
import random
import sys
import time
from copy import deepcopy
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

sys.path.insert(0, "/work/notes/runs")
import voice6_exp as v6  # noqa: E402
import voice_exp as ve  # noqa: E402

from services.voice import enrol  # noqa: E402
from services.voice.spotter.features import Embedder  # noqa: E402
from services.voice.spotter.head import SURE_CONFIDENCE, Head  # noqa: E402
from services.voice.training import corpus, dataset, train  # noqa: E402
from services.voice.training.train import TrainConfig, calibrate, fit_temperature  # noqa: E402

OUT = Path("/tmp/voice9")
OUT.mkdir(exist_ok=True)
WORDS = corpus.VOCABULARY
OTHER = len(WORDS)
CFG = TrainConfig()
CALIB_SPLITS = ("tune", "neighbours-tune", "speakers-tune")


class CachingEmbedder(Embedder):
    """Embedder.utterance memoised by (audio, seed): recipes differ only in the fit, not in the features."""

    def __init__(self) -> None:
        super().__init__()
        self._memo: dict[tuple[str, int], np.ndarray] = {}

    def utterance(self, pcm: bytes, seed: int = 0):  # type: ignore[override]
        k = (hashlib.sha1(pcm).hexdigest(), seed)
        if k not in self._memo:
            self._memo[k] = super().utterance(pcm, seed=seed)
        return self._memo[k]


EMB = CachingEmbedder()
enrol._anchor_audio = lru_cache(maxsize=None)(enrol._anchor_audio)  # render the espeak anchors once


def stats(rot: str) -> tuple[np.ndarray, np.ndarray]:
    path = OUT / f"stats-{rot}.npz"
    if not path.exists():
        x, y, v, _, _ = ve.load(ve.TRAIN_SPLITS)
        keep = v != v6.ROT[rot]
        _, _, _, mean, scale = v6.prepare(x[keep], y[keep], CFG)
        np.savez(path, mean=mean, scale=scale, rows=int(keep.sum()))
    d = np.load(path)
    return d["mean"], d["scale"]


def left_out_head(rot: str, tune) -> Head:
    tx, ty, tv, tn, _ = tune
    members = []
    for s in (12, 13, 14):
        z = np.load(Path("/tmp/voice8") / f"base-{rot}-s{s}.npz")
        members.append(([z["w0"], z["w1"]], [z["b0"], z["b1"]]))
    mean, scale = stats(rot)
    head = v6.head_of(members, mean, scale, CFG)
    cal = np.isin(tn, CALIB_SPLITS) & (tv != v6.ROT[rot])
    fit_temperature(head, tx[cal], ty[cal])
    calibrate(head, tx[cal], ty[cal], CFG)
    head.meta = {"rotation": rot}
    return head


def user_samples(rot: str, with_others: bool, offset: int = 0, reps: int = 1, draw: int = 0) -> list[tuple[str, bytes]]:
    """5 per command by d (+ the prompt list once each), rendered once and cached. `draw` > 0: another independent
    set (other seeds, speeds, pitches)."""
    tag = f"-d{draw}" if draw else ""
    path = OUT / f"enrol-samples-{rot}{tag}.pickle"
    if path.exists():
        cache = pickle.loads(path.read_bytes())
    else:
        voice = v6.ROT[rot]
        rng = random.Random(f"voice9:{rot}" + tag)
        cmds = []
        for i, word in enumerate(WORDS):
            for k in range(5):
                r = dataset.Recipe(word, i, voice, round(rng.uniform(0.9, 1.1), 3), round(rng.uniform(0.9, 1.1), 3),
                                   50_000 + 1000 * draw + 7 * i + k, 0.0 if k < 3 else 1.0)
                cmds.append((word, dataset.render_utterance(r)))
        others = {}
        for j, word in enumerate(prompt_list()):
            r = dataset.Recipe(word, OTHER, voice, round(rng.uniform(0.9, 1.1), 3), round(rng.uniform(0.9, 1.1), 3),
                               60_000 + 1000 * draw + j, 0.0)
            others[word] = dataset.render_utterance(r)
        cache = {"cmds": cmds, "others": others}
        path.write_bytes(pickle.dumps(cache))
    out = list(cache["cmds"])
    if with_others:
        missing = [w for w in prompt_list(offset) if w not in cache["others"]]
        for j, word in enumerate(missing):  # later lists: rendered on demand, their own seeds
            rng = random.Random(f"voice9:{rot}:{word}" + tag)
            r = dataset.Recipe(word, OTHER, v6.ROT[rot], round(rng.uniform(0.9, 1.1), 3), round(rng.uniform(0.9, 1.1), 3),
                               61_000 + 1000 * draw + 100 * offset + j, 0.0)
            cache["others"][word] = dataset.render_utterance(r)
        if missing:
            path.write_bytes(pickle.dumps(cache))
        for word in prompt_list(offset):
            out.append(("other", cache["others"][word]))
        if reps == 2:  # each prompt word said a second time: its own seed, speed and pitch
            key = f"again:{offset}"
            if key not in cache:
                again = {}
                for j, word in enumerate(prompt_list(offset)):
                    rng = random.Random(f"voice9-again:{rot}:{word}" + tag)
                    r = dataset.Recipe(word, OTHER, v6.ROT[rot], round(rng.uniform(0.9, 1.1), 3),
                                       round(rng.uniform(0.9, 1.1), 3), 62_000 + 1000 * draw + 100 * offset + j, 0.0)
                    again[word] = dataset.render_utterance(r)
                cache[key] = again
                path.write_bytes(pickle.dumps(cache))
            out += [("other", cache[key][w]) for w in prompt_list(offset)]
    return out


def forbidden_prompt_words() -> set[str]:
    """Words that may never be prompted: tune and held-out non-commands (either split, any form), the scored
    words of recorded-tune, commands and their homophones, and words that contain a command."""
    nb = dataset.neighbours(dataset.Sizes(), ve.SEED)
    from services.voice.synth import OOV_HELDOUT, OOV_TUNE
    bad = set(OOV_TUNE) | set(OOV_HELDOUT) | set(nb["tune"]) | set(nb["heldout"]) | set(corpus.forbidden_negatives())
    return bad


@lru_cache(maxsize=None)
def prompt_list(offset: int = 0) -> tuple[str, ...]:
    """Rule: per command, the first two words of corpus.NEIGHBOURS_TRAIN[command] (its listed order) that are one
    word, do not contain a command word, and are no tune or held-out word."""
    bad = forbidden_prompt_words()
    out = []
    for cmd in WORDS:
        picked = [w for w in corpus.NEIGHBOURS_TRAIN[cmd]
                  if w.isalpha() and w not in bad and not any(c in w for c in WORDS)][offset : offset + 2]
        out += picked
    return tuple(out)


def decide(head: Head, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(published class or -1, published confidence) per row, as SpotterEngine.recognise."""
    p = head.probabilities(x)
    n = len(head.vocabulary)
    best = p.argmax(axis=1)
    top = p[:, :n].argmax(axis=1)
    conf = np.array([head.confidence(int(t), float(p[i, t])) for i, t in enumerate(top)])
    pub = np.where((best < n) & (conf >= 0.5), best, -1)
    go = WORDS.index("go")
    if head.base_last is not None:
        pb = head.probabilities(x, base=True)
        for i in np.where((pub == go) & (conf >= SURE_CONFIDENCE))[0]:
            if head.confidence(go, float(pb[i, go])) < SURE_CONFIDENCE:
                conf[i] = SURE_CONFIDENCE - 0.01
    conf = np.where(best < n, conf, np.minimum(conf, 0.49))
    return pub, conf


def figures(head: Head, x: np.ndarray, y: np.ndarray) -> dict:
    pub, conf = decide(head, x)
    cmd = y < OTHER
    go = WORDS.index("go")
    yes = WORDS.index("yes")
    return {"acc": round(float(np.mean(pub[cmd] == y[cmd])), 3),
            "oov_acc": round(float(np.mean(pub[~cmd] >= 0)), 3),
            "n_oov_acc": int(np.sum(pub[~cmd] >= 0)), "n_oov": int((~cmd).sum()),
            "false_walk": int(np.sum((pub == go) & (y != go) & (conf >= 0.85))),
            "false_ask": int(np.sum((pub == go) & (y != go) & (conf < 0.85))),
            "go_walk": round(float(np.mean((pub == go)[y == go] & (conf[y == go] >= 0.85))), 3),
            "conf_yes_non_yes": int(np.sum((pub == yes) & (y != yes) & (conf >= 0.7)))}


def replace_knots(before: Head, after: Head, user_other: np.ndarray, min_gap: float = 1e-4) -> Head:
    """Accept knots raised (never lowered) to just above the highest probability any of the user's own "other"
    samples reaches for that command under the adapted head; sure knots kept (at least accept + 0.01)."""
    h = deepcopy(after)
    if len(user_other):
        p = h.probabilities(user_other)
        for c in range(len(h.vocabulary)):
            worst = float(p[:, c].max())
            h.accept[c] = max(float(before.accept[c]), worst + min_gap)
            h.sure[c] = max(float(h.sure[c]), h.accept[c] + 0.01)
    return h


def parse(spec: str) -> tuple[str, dict[str, str]]:
    name, *kvs = spec.split(",")
    return name, dict((kv.split("=") + [""])[:2] for kv in kvs)


def run(spec: str, heads: dict, tune) -> dict:
    tx, ty, tv, tn, tt = tune
    name, kw = parse(spec)
    cfg = enrol.EnrolConfig()
    cfg = replace(cfg, prior=float(kw.get("prior", cfg.prior)), steps=int(kw.get("steps", cfg.steps)),
                  copies=int(kw.get("copies", cfg.copies)), reversed_others=int(kw.get("rev", cfg.reversed_others)),
                  anchors=bool(int(kw.get("anchors", 1))))
    with_others = bool(int(kw.get("others", 0)))
    offset = int(kw.get("offset", 0))
    reps = int(kw.get("reps", 1))
    if "ow" in kw:  # round 2 only: EnrolConfig.other_weight existed (uncommitted) while S1, S2, S5 ran; not committed
        cfg = replace(cfg, other_weight=float(kw["ow"]))
    rows = {}
    for rot, head in heads.items():
        d = v6.ROT[rot]
        m = (tn == "recorded-tune") & (tv == d)
        scored_words = set(tt[m & (ty == OTHER)])
        assert not scored_words & set(prompt_list()), scored_words & set(prompt_list())
        samples = user_samples(rot, with_others, offset, reps, int(kw.get("draw", 0)))
        if int(kw.get("both", 0)):  # the prompt list and the next one
            samples += [s for s in user_samples(rot, True, 2) if s[0] == "other"]
        t0 = time.time()
        adapted = enrol.adapt(head, samples, cfg, embedder=EMB)
        secs = time.time() - t0
        if int(kw.get("knots", 0)):
            own = [pcm for label, pcm in samples if label == "other"]
            own += [np.frombuffer(pcm, dtype="<i2")[::-1].tobytes() for label, pcm in samples if label != "other"]
            feats = np.stack([EMB.utterance(p) for p in own]) if own else np.zeros((0, 16, 96))
            adapted = replace_knots(head, adapted, feats)
        spoken = set(enrol.ANCHOR_WORDS) | set(prompt_list()) | set(prompt_list(2))
        ms = m & ~((ty == OTHER) & np.isin(tt, list(spoken)))  # enrolment words never scored (the rule's figure)
        rows[rot] = {"before": figures(head, tx[ms], ty[ms]), "after": figures(adapted, tx[ms], ty[ms]),
                     "after_anchor_words_scored": figures(adapted, tx[m], ty[m]),
                     "before_anchor_words_scored": figures(head, tx[m], ty[m]), "adapt_s": round(secs, 1)}
    mean = {k: {f: round(float(np.mean([rows[r][k][f] for r in rows])), 3) for f in ("acc", "oov_acc")}
            for k in ("before", "after")}
    walks = {k: sum(rows[r][k]["false_walk"] for r in rows) for k in ("before", "after")}
    asks = {k: sum(rows[r][k]["false_ask"] for r in rows) for k in ("before", "after")}
    return {"recipe": spec, "mean": mean, "false_walks": walks, "false_asks": asks, "rows": rows}


def main() -> None:
    t0 = time.time()
    tune = ve.load(train.TUNE_SPLITS)
    heads = {rot: left_out_head(rot, tune) for rot in v6.ROT}
    print(json.dumps({"prompt_list": prompt_list(), "next_list": prompt_list(2), "setup_s": round(time.time() - t0)}), flush=True)
    for spec in sys.argv[1:]:
        print(json.dumps(run(spec, heads, tune)), flush=True)


if __name__ == "__main__":
    main()
