"""Round voice38, tuning data only: a quiet utterance brought up to a trained level before the spotter hears it.

Round voice37b's held-out runs (seed 7183) showed that quiet speech which is segmented is also taken for a command
more often: other words 14-15 % at -38 and -32 dBFS peak, 7-10 % at trained levels. The spotter was trained on clips
peaking from -26 to -2 dBFS. This measures, on tuning clips only, whether it hears quiet ones better when each
utterance whose peak is under a level is first scaled so that its peak sits at a trained level (the hiss with it).

The clips: round voice36's cache of the `tune` and `neighbours-tune` splits (train seed 12), drawn as round voice37's
tuning script draws them; each at each quiet peak level with a quiet room's hiss (-70 dBFS RMS) 0.2 s either side,
as `bench/voice_levels.py`'s file path, heard by the default engine as it comes and brought up to each target.

    .venv/bin/python docs/experiments/scripts/voice38_tune.py --targets -26,-20,-14 --json /tmp/s71/voice38_tune.json
    .venv/bin/python docs/experiments/scripts/voice38_tune.py --peaks -44,-26 --targets= --floor -100   # no hiss

(-44 dBFS brought up to -26 is -26 dBFS speech in hiss 18 dB higher, -52 dBFS: the row "hiss at -52" of the README.)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402

from bench.voice_bench import OTHER, Item, Policy  # noqa: E402,F401
from bench.voice_levels import run_files  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s71/voice36_tune_clips.pickle"))
    ap.add_argument("--peaks", default="-44,-38,-32")
    ap.add_argument("--targets", default="-26,-20,-14", help="the peak a quiet utterance is brought up to (dBFS)")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss, dBFS RMS")
    ap.add_argument("--per-command", type=int, default=40)
    ap.add_argument("--others", type=int, default=200)
    ap.add_argument("--seed", type=int, default=37)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    items = tune_items(args.cache, args.per_command, args.others, args.seed)
    print(f"{sum(i.label < OTHER for i in items)} commands, {sum(i.label == OTHER for i in items)} other words", flush=True)
    policy = Policy.from_knowledge()
    engine = make_engine("spotter")
    rows = []
    for peak in (float(p) for p in args.peaks.split(",")):
        for target in [None, *(float(t) for t in args.targets.split(",") if t)]:
            gain = 0.0 if target is None else target - peak
            row = {"peak_dbfs": peak, "floor_dbfs": args.floor, "target_dbfs": target,
                   **run_files(engine, items, peak, args.floor, gain, policy, args.seed)}
            rows.append(row)
            print(json.dumps({k: row[k] for k in ("peak_dbfs", "floor_dbfs", "target_dbfs", "command_accuracy", "oov_accepted",
                                                  "false_walks", "top_errors")}), flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
