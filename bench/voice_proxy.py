"""The spotter's unseen-speaker tuning proxy: leave one recorded training speaker out (tuning data only).

For each recorded training speaker d (`corpus.RECORDED_TRAIN`: flite kal16, flite awb, Festival ked) the
committed recipe (`TrainConfig()`, the splits `train` fits on) is fitted WITHOUT d and d's virtual speakers
(`d@vtl...`): one MLP per seed, exactly `train.fit`'s members (`train.crop_rows`, `train.fit_member`, BLAS pinned
to `TrainConfig.blas_threads`), combined as `train.fit` combines them (`train.ensemble`). Then, never with d's
clips in the calibration either:

- plain proxy (rounds 5-8 of docs/experiments/voice-rounds.md): temperature and knots (`train.fit_temperature`,
  `train.calibrate`) fitted on one random half of the tune rows without d, figures (`train.tune_figures`) on
  d's `recorded-tune` clips of the other half, both ways, averaged;
- `--enrol` (round 9): temperature and knots on all of `TrainConfig.tune_splits` without d, as `train` does;
  then d "enrols" (`enrol.adapt`, the committed `EnrolConfig`) with five fresh samples per command (speed and
  pitch x0.9-1.1, three clean and two augmented) and the prompted non-command words (`enrol.PROMPT_OTHERS`,
  `PROMPT_REPEATS` times, clean), and d's `recorded-tune` clips are scored before and after through the
  engine's decision (`SpotterEngine.recognise`) and the reasoner's policy (`voice_bench.Policy`), without the
  words said at enrolment (the espeak anchors `enrol.ANCHOR_WORDS` and the prompted words).

`--foreign N` (round 11): the same, with the `foreign` split (`corpus.FOREIGN_TRAIN`: Czech and Finnish recorded
speakers saying the English words, N clips per command) added to the training rows of every rotation; those
voices are never left out, calibrated on or scored.

Features come from the training caches (`dataset.indexed_features`, `HRI_VOICE_CACHE`); nothing is rendered
for the plain proxy. Fitting one rotation (three members) takes 4-18 min on two shared cores: `--members-dir`
keeps them (`<speaker>-s<seed>.npz`, with the recipe they were fitted on; a file fitted on other data or
settings is refused). The held-out split is never read.

    nice -n 10 .venv/bin/python bench/voice_proxy.py --members-dir /tmp/voice-proxy
    nice -n 10 .venv/bin/python bench/voice_proxy.py --members-dir /tmp/voice-proxy --enrol --draws 0 --draws 1 --draws 2
    nice -n 10 .venv/bin/python bench/voice_proxy.py --members-dir /tmp/voice-proxy-foreign --foreign 360
"""

from __future__ import annotations

import copy
import hashlib
import json
import random
import sys
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from services.voice.spotter.head import Head
from services.voice.training import corpus, dataset, train, tts
from services.voice.training.train import TrainConfig

WORDS = corpus.VOCABULARY
OTHER = len(WORDS)
SPEAKERS = {v.partition(":")[2]: v for v in corpus.RECORDED_TRAIN}
"""Short names (kal16, awb, ked) of the recorded training speakers."""
CALIBRATION_SEED = 0
"""The random halves of the tune rows (`numpy.random.default_rng(0)`, as rounds 5-8 drew them)."""


def speaker(voice: str) -> str:
    """The recorded (or espeak) voice a clip's voice is made from: `flite:awb@vtl1.1` -> `flite:awb`."""
    return tts.base_voice(voice)


@dataclass
class Rows:
    x: np.ndarray
    y: np.ndarray
    voice: np.ndarray
    """The clip's voice as rendered (virtual speakers with their `@vtl` factor)."""
    split: np.ndarray
    text: np.ndarray

    def speakers(self) -> np.ndarray:
        return np.array([speaker(v) for v in self.voice])

    def __getitem__(self, m: np.ndarray) -> Rows:
        return Rows(self.x[m], self.y[m], self.voice[m], self.split[m], self.text[m])


def load(splits: tuple[str, ...], cfg: TrainConfig) -> Rows:
    """The cached features of these splits, with each row's voice, split and text."""
    x, y, rows, names = dataset.split_rows(splits, cfg.sizes, cfg.seed, cfg.workers, progress=False,
                                           embedding=cfg.embedding)
    return Rows(x, y, np.array([r.voice for r in rows]), np.array(names), np.array([r.text for r in rows]))


def without(rows: Rows, d: str) -> np.ndarray:
    """Rows not by speaker d nor by any virtual speaker made from d."""
    return rows.speakers() != d


def left_out(rows: Rows, d: str) -> np.ndarray:
    """d's own `recorded-tune` clips: what the proxy scores."""
    return (rows.split == "recorded-tune") & (rows.voice == d)


def calibration_rows(rows: Rows, d: str, cfg: TrainConfig) -> np.ndarray:
    """The rows `train` calibrates on (`TrainConfig.tune_splits`), without d and d's virtual speakers."""
    return np.isin(rows.split, cfg.tune_splits) & without(rows, d)


def recipe_key(rows: Rows, d: str, seed: int, cfg: TrainConfig) -> str:
    """What a member is fitted on and how, to refuse a cached member of another recipe or other data."""
    keep = without(rows, d)
    return json.dumps({"left_out": d, "seed": seed, "embedding": cfg.embedding, "hidden": cfg.hidden,
                       "alpha": cfg.alpha, "balance": cfg.balance, "crop_width": cfg.crop_width,
                       "crop_starts": list(cfg.crop_starts), "rows": int(keep.sum()),
                       "data": hashlib.sha1(rows.x[keep].tobytes() + rows.y[keep].tobytes()).hexdigest()[:16],
                       "splits": sorted(set(rows.split.tolist()))}, sort_keys=True)


def fitted_head(rows: Rows, d: str, seeds: list[int], cfg: TrainConfig, members_dir: Path | None) -> tuple[Head, dict]:
    """The ensemble of `seeds` fitted without d (members read from / written to `members_dir`)."""
    keep = without(rows, d)
    flat, y, weight, mean, scale = train.crop_rows(rows.x[keep], rows.y[keep], cfg)
    members, info = [], {}
    for seed in seeds:
        path = members_dir / f"{d.partition(':')[2]}-s{seed}.npz" if members_dir else None
        key = recipe_key(rows, d, seed, cfg)
        if path is not None and path.exists():
            z = np.load(path)
            if str(z["recipe"]) != key:
                raise typer.BadParameter(f"{path} was fitted on another recipe or other data:\n{z['recipe']}\nnot\n{key}")
            members.append(([z["w0"], z["w1"]], [z["b0"], z["b1"]], int(z["n_iter"])))
            info[seed] = {"cached": True, "n_iter": int(z["n_iter"]), "blas_threads": int(z["blas_threads"])}
            continue
        w, b, n_iter = train.fit_member(flat, y, weight, cfg, seed)
        # Kept as float32 and combined from float32 (as the rounds' members were): the head's arithmetic is
        # the same whether a member was just fitted or read back.
        member = ([a.astype(np.float32) for a in w], [a.astype(np.float32) for a in b], n_iter)
        members.append(member)
        info[seed] = {"cached": False, "n_iter": n_iter, "blas_threads": cfg.blas_threads}
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            np.savez(path, w0=member[0][0], w1=member[0][1], b0=member[1][0], b1=member[1][1], n_iter=n_iter,
                     blas_threads=cfg.blas_threads, recipe=key)
    return train.ensemble(members, mean, scale, cfg), {"train_rows": int(keep.sum()), "members": info}


def calibrated(head: Head, tune: Rows, mask: np.ndarray, cfg: TrainConfig) -> Head:
    h = copy.deepcopy(head)
    train.fit_temperature(h, tune.x[mask], tune.y[mask])
    train.calibrate(h, tune.x[mask], tune.y[mask], cfg)
    return h


def plain(head: Head, tune: Rows, d: str, cfg: TrainConfig) -> dict[str, dict[str, float]]:
    """Rounds 5-8's figures: knots on one random half of the tune rows without d, figures on the other half
    (d's recorded-tune clips; and the `tune` split's clips), both ways, averaged.

    As in those rounds, the halves are drawn over every row of `train.TUNE_SPLITS`, so the calibration half
    also holds the `recorded-tune` clips of the two other recorded speakers (`train` itself calibrates on
    `TrainConfig.tune_splits`, without `recorded-tune`): kept so that the bench reproduces the rounds' figures."""
    half = np.random.default_rng(CALIBRATION_SEED).random(len(tune.y)) < 0.5
    scored = {"left_out": left_out(tune, d), "tune": tune.split == "tune"}
    figs: dict[str, list[dict[str, float]]] = {k: [] for k in scored}
    for a in (half, ~half):
        h = calibrated(head, tune, a & without(tune, d), cfg)
        for k, m in scored.items():
            if (~a & m).any():
                figs[k].append(train.tune_figures(h, tune.x[~a & m], tune.y[~a & m]))
    return {k: {f: round(float(np.mean([g[f] for g in v])), 3) for f in v[0]} for k, v in figs.items() if v}


class _Rows:
    """An embedder whose 'audio' is a row number: lets `SpotterEngine.recognise` decide on cached features."""

    def __init__(self, x: np.ndarray) -> None:
        self.x = x

    def utterance(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        return self.x[int.from_bytes(pcm, "little")]


def decide(head: Head, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(published class or -1, published confidence) per row, by the engine itself."""
    from services.voice.engine_spotter import SpotterEngine

    engine = SpotterEngine(head, embedder=_Rows(x))  # type: ignore[arg-type]
    pub, conf = np.full(len(x), -1), np.zeros(len(x))
    for i in range(len(x)):
        rec = engine.recognise(i.to_bytes(4, "little"))  # 4 bytes: far below the long-utterance limit
        if rec.command is not None:
            pub[i] = WORDS.index(rec.command.value)
        conf[i] = rec.confidence
    return pub, conf


def enrol_figures(head: Head, x: np.ndarray, y: np.ndarray, policy: object) -> dict[str, float]:
    """Command accuracy (the right command published), non-commands accepted (any command published), and the
    "go"s published on other clips that walk (confidence >= confirm_below) or ask (min_confidence..confirm_below)."""
    pub, conf = decide(head, x)
    cmd = y < OTHER
    go = WORDS.index("go")
    false_go = (pub == go) & (y != go) & (conf >= policy.min_confidence)  # type: ignore[attr-defined]
    walks = conf >= policy.confirm_below  # type: ignore[attr-defined]
    return {"command_accuracy": round(float(np.mean(pub[cmd] == y[cmd])), 3),
            "other_accepted": round(float(np.mean(pub[~cmd] >= 0)), 3),
            "n_other_accepted": int(np.sum(pub[~cmd] >= 0)), "n_other": int((~cmd).sum()),
            "false_go_walk": int(np.sum(false_go & walks)), "false_go_ask": int(np.sum(false_go & ~walks))}


def user_samples(d: str, draw: int) -> list[tuple[str, bytes]]:
    """d's enrolment: five samples per command, then the prompted words. The random stream ("voice9:<name>") and
    the seeds (50,000 + ..., 60,000 + ...) are round 9's, so that draw 0, 1, 2 are its three draws; none is the
    seed of a scored clip (those are drawn by `dataset.recipes`, below 2**31 at random)."""
    from services.voice.enrol import PROMPT_OTHERS, PROMPT_REPEATS

    rng = random.Random(f"voice9:{d.partition(':')[2]}" + (f"-d{draw}" if draw else ""))
    out = []
    for i, word in enumerate(WORDS):
        for k in range(5):
            r = dataset.Recipe(word, i, d, round(rng.uniform(0.9, 1.1), 3), round(rng.uniform(0.9, 1.1), 3),
                               50_000 + 1000 * draw + 7 * i + k, 0.0 if k < 3 else 1.0)
            out.append((word, dataset.render_utterance(r)))
    for rep in range(PROMPT_REPEATS):
        for j, word in enumerate(PROMPT_OTHERS):
            r = dataset.Recipe(word, OTHER, d, round(rng.uniform(0.9, 1.1), 3), round(rng.uniform(0.9, 1.1), 3),
                               60_000 + 1000 * draw + 100 * rep + j, 0.0)
            out.append(("other", dataset.render_utterance(r)))
    return out


def enrolment(head: Head, tune: Rows, d: str, draws: list[int], cfg: TrainConfig) -> dict[str, object]:
    from voice_bench import Policy

    from services.voice import enrol

    policy = Policy.from_knowledge()
    h = calibrated(head, tune, calibration_rows(tune, d, cfg), cfg)
    spoken = set(enrol.ANCHOR_WORDS) | set(enrol.PROMPT_OTHERS)
    m = left_out(tune, d) & ~((tune.y == OTHER) & np.isin(tune.text, list(spoken)))
    out: dict[str, object] = {"before": enrol_figures(h, tune.x[m], tune.y[m], policy)}
    for draw in draws:
        adapted = enrol.adapt(h, user_samples(d, draw))
        out[f"after_draw{draw}"] = enrol_figures(adapted, tune.x[m], tune.y[m], policy)
    return out


def mean_row(rows: dict[str, dict], key: str) -> dict[str, float]:
    figs = [r[key] for r in rows.values()]
    out = {f: round(float(np.mean([g[f] for g in figs])), 3) for f in ("command_accuracy", "other_accepted")}
    out.update({f: round(float(np.sum([g[f] for g in figs])), 1) for f in ("false_go_ask", "false_go_walk")})
    return out


def main(
    speakers: Annotated[list[str] | None, typer.Option(
        help="Recorded training speakers to leave out, one at a time (default: all of " + ", ".join(SPEAKERS) + ")")] = None,
    seeds: Annotated[list[int] | None, typer.Option(
        help="Seeds of the ensemble's members (default: 12, 13, 14, as train.fit's)")] = None,
    members_dir: Annotated[Path | None, typer.Option(help="Reuse / keep the fitted members here")] = None,
    enrol: Annotated[bool, typer.Option(help="The enrolment proxy (round 9) instead of the plain one")] = False,
    draws: Annotated[list[int] | None, typer.Option(help="Enrolment draws (--enrol; default: 0)")] = None,
    json_out: Annotated[Path | None, typer.Option("--json", help="Also write the figures here")] = None,
    foreign: Annotated[int, typer.Option(
        help="Round 11's variant: also fit on the `foreign` split (recorded speakers of other languages, "
             "corpus.FOREIGN_TRAIN) with this many clips per command (0: the committed recipe)")] = 0,
    embedding: Annotated[str | None, typer.Option(
        help="Round 13's variant: the speech embedding (whisper-tiny.en: no crops) [default: the committed recipe's]")] = None,
) -> None:
    """The leave-one-recorded-speaker-out proxy of the committed recipe (see the module's docstring)."""
    speakers = speakers or list(SPEAKERS)
    seeds = seeds or [12, 13, 14]
    draws = draws or [0]
    cfg = TrainConfig(sizes=replace(dataset.Sizes(), foreign_positives=foreign)) if foreign else TrainConfig()
    if embedding is not None and embedding != cfg.embedding:
        try:
            cfg = train.on_embedding(cfg, embedding)
        except ValueError as exc:
            raise typer.BadParameter(str(exc), param_hint="--embedding") from None
    unknown = [s for s in speakers if s not in SPEAKERS]
    if unknown:
        raise typer.BadParameter(f"unknown speakers {unknown}: choose from {list(SPEAKERS)}")
    rows = load(train.training_splits(cfg.sizes), cfg)
    tune = load(train.TUNE_SPLITS, cfg)
    result: dict[str, dict] = {}
    for name in speakers:
        d = SPEAKERS[name]
        head, info = fitted_head(rows, d, seeds, cfg, members_dir)
        figs = enrolment(head, tune, d, draws, cfg) if enrol else plain(head, tune, d, cfg)
        result[name] = {**figs, **info}
        print(json.dumps({"speaker": d, **result[name]}), flush=True)
    keys = ["before", *(f"after_draw{k}" for k in draws)] if enrol else ["left_out", "tune"]
    summary = {k: mean_row(result, k) for k in keys}
    print()
    print(f"{'figures':22} " + " ".join(f"{n:>15}" for n in speakers) + f" {'mean':>13} {'false go ask/walk':>18}")
    for k in keys:
        cells = " ".join(f"{result[n][k]['command_accuracy']:6.3f} / {100 * result[n][k]['other_accepted']:4.1f} %"
                         for n in speakers)
        s = summary[k]
        print(f"{k:22} {cells} {s['command_accuracy']:6.3f} / {100 * s['other_accepted']:4.1f} %"
              f" {s['false_go_ask']:>8} / {s['false_go_walk']}")
    print("(accuracy / non-commands accepted; false go: summed over speakers"
          + (", means over the two calibration halves)" if not enrol else ")"))
    if json_out:
        json_out.write_text(json.dumps({"config": {"seeds": seeds, "enrol": enrol, "draws": draws,
                                                   "train_config": asdict(cfg)}, "speakers": result,
                                        "mean": summary}, indent=2, default=str))


if __name__ == "__main__":
    typer.run(main)
