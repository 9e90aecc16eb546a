"""Round voice36, tuning data only: each utterance's peak brought to one level before the spotter hears it.

The tune splits the default head's knots were placed on (`dataset.recipes`, train seed 12: `tune` and
`neighbours-tune`), rendered as training renders them (peaks drawn from -26 to -1 dBFS), heard by the committed
default engine as they come (control) and with each clip's peak brought to each level first (`at_peak`). Scored as the bench scores:
commands heard (the reasoner's policy takes them; an asked "go" counted apart), other words taken, walks.

    .venv/bin/python docs/experiments/scripts/voice36_tune.py --levels -32,-26,-20,-14 --json /tmp/s70/voice36_tune.json
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import pickle
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from bench.voice_bench import ASK, OTHER, WALK, WORDS, Policy  # noqa: E402
from services.voice.audio import from_pcm, to_pcm  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.training import dataset, tts  # noqa: E402


def _render(r: dataset.Recipe) -> tuple[int, str, bytes] | None:
    try:
        pcm = dataset.render(r)
    except tts.TtsError:
        return None
    return None if pcm is None else (r.label, r.text, pcm)


def clips(seed: int, workers: int, cache: Path) -> list[tuple[int, str, bytes]]:
    if cache.exists():
        return pickle.loads(cache.read_bytes())
    sizes = dataset.Sizes()
    jobs = [r for split in ("tune", "neighbours-tune") for r in dataset.recipes(split, sizes, seed) if r.voice]
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        out = [c for c in pool.map(_render, jobs, chunksize=16) if c is not None]
    cache.write_bytes(pickle.dumps(out))
    return out


def at_peak(pcm: bytes, peak_dbfs: float | None) -> bytes:
    """16-bit PCM scaled so that its peak is `peak_dbfs` dBFS (None: as it is)."""
    x = from_pcm(pcm)
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    return pcm if peak_dbfs is None or peak == 0.0 else to_pcm(x * (10 ** (peak_dbfs / 20) / peak))


def score(engine, items: list[tuple[int, str, bytes]], policy: Policy, level: float | None) -> dict[str, object]:
    heard = asked = total = oov = taken = walks = 0
    per: Counter[str] = Counter()
    per_total: Counter[str] = Counter()
    for label, _text, pcm in items:
        rec = engine.recognise(at_peak(pcm, level))
        took = policy.takes(rec.command, rec.confidence)
        if label < OTHER:
            word = WORDS[label]
            total += 1
            per_total[word] += 1
            ok = rec.command is not None and rec.command.value == word and took is not None
            heard += ok
            asked += ok and took == ASK
            per[word] += ok
        else:
            oov += 1
            taken += took is not None
            walks += took == WALK
    return {"commands_heard": round(heard / max(1, total), 4), "asked_go": asked, "other_taken": round(taken / max(1, oov), 4),
            "walks": walks, "by_command": {w: round(per[w] / max(1, per_total[w]), 3) for w in WORDS},
            "n": {"commands": total, "other": oov}}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--levels", default="-32,-26,-20,-14")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/voice36_tune_clips.pickle"))
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    items = clips(args.seed, args.workers, args.cache)
    print(f"{len(items)} tune clips", flush=True)
    policy = Policy.from_knowledge()
    engine = make_engine("spotter")
    rows = []
    for level in [None, *(float(v) for v in args.levels.split(","))]:
        row = {"level_dbfs": level, **score(engine, items, policy, level)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
