"""Round voice50c, tuning data only: each utterance of `bench/voice_long_stream.py`'s tuning stream, kept with the
segmenter's speech-to-noise estimate, so that rules on it can be scored offline.

`record` runs one stream (one peak, one floor, one way of `voice_long_stream.way_config`) through the service's path
as the bench's `heard` does, and writes every utterance (start, end, `snr_db`, command, confidence, when it was handed
over) and every word said (label, start, end) to a JSON file. `score` scores those files as the bench does (commands
heard, other words accepted, false walks, latency p50 ms) and, with `--sweep`, with a noisy utterance's command
refused below a confidence (a bar in dB under which an utterance counts as noisy, by `snr_db`): the recogniser-side
candidate this round looked at first and made none of (voice README, stop 93).

    .venv/bin/python docs/experiments/scripts/voice50c_tune.py record -- -38 -70 fresh1 /tmp/s93/t_-38_-70_fresh1.json
    .venv/bin/python docs/experiments/scripts/voice50c_tune.py score --sweep /tmp/s93/t_*_fresh1.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import ASK, OTHER, WALK, WORDS, Policy  # noqa: E402
from bench.voice_long_stream import hearings, long_stream, picked, tuning_items, way_config  # noqa: E402
from schemas.messages import Command  # noqa: E402
from services.voice.engine import make_engine, one_blas_thread  # noqa: E402


def record(peak: float, floor: float, way: str, out: Path) -> None:
    one_blas_thread()
    items = picked(tuning_items(0), 150, 0)
    engine = make_engine("spotter")
    pcm, placed = long_stream(items, peak, floor, 20.0, 0)
    utts = [{"start": h.start_s, "end": h.end_s, "snr": h.snr_db, "emitted": h.emitted_s,
             "command": h.recognition.command.value if h.recognition.command else None,
             "conf": h.recognition.confidence} for h in hearings(engine, pcm, way_config(way))]
    words = [{"word": WORDS[p.item.label] if p.item.label < OTHER else None, "text": p.item.text,
              "start": p.start_s, "end": p.end_s} for p in placed]
    out.write_text(json.dumps({"peak": peak, "floor": floor, "way": way, "utts": utts, "words": words}))


def score(data: dict[str, Any], refuse: Callable[[dict[str, Any]], bool] | None = None) -> tuple[int, int, int, float]:
    """Commands heard, other words accepted, false walks, latency p50 (ms), as `voice_long_stream.heard` counts them;
    `refuse(utterance)`: its command is dropped."""
    policy = Policy.from_knowledge()
    taken = [(u["start"], u["end"], None if refuse is not None and refuse(u) else
              policy.takes(None if u["command"] is None else Command(u["command"]), u["conf"]), u["emitted"])
             for u in data["utts"]]
    right = accepted = walks = 0
    latency = []
    for w in data["words"]:
        over = [t for t in taken if t[0] < w["end"] + 0.15 and t[1] > w["start"]]
        walks += w["word"] != "go" and any(t[2] == WALK for t in over)
        if w["word"] is None:
            accepted += any(t[2] is not None for t in over)
            continue
        hits = [t for t in over if t[2] is not None and (t[2] == w["word"] or (w["word"] == "go" and t[2] in (WALK, ASK)))]
        right += bool(hits)
        if hits:
            latency.append(hits[0][3] - w["end"])
    return right, accepted, walks, round(float(np.median(latency)) * 1000.0) if latency else float("nan")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("peak", type=float)
    rec.add_argument("floor", type=float)
    rec.add_argument("way")
    rec.add_argument("out", type=Path)
    sc = sub.add_parser("score")
    sc.add_argument("files", type=Path, nargs="+")
    sc.add_argument("--sweep", action="store_true")
    args = ap.parse_args()
    if args.what == "record":
        record(args.peak, args.floor, args.way, args.out)
        return 0
    data = {f.name: json.loads(f.read_text()) for f in args.files}
    base = {name: score(d) for name, d in data.items()}
    for name, row in base.items():
        print(name, "heard / others / walks / p50 ms:", row)
    if args.sweep:
        print("noisy below (dB), confidence under which refused: change in commands heard / other words, per file")
        for bar in (16.0, 18.0, 20.0, 22.0, 24.0, 26.0):
            for least in (0.55, 0.6, 0.65, 0.7, 0.75, 0.8):
                cells = []
                for name, d in data.items():
                    r = score(d, lambda u, bar=bar, least=least: u["snr"] is not None and u["snr"] < bar
                              and u["conf"] < least)
                    cells.append(f"{r[0] - base[name][0]:+d}/{r[1] - base[name][1]:+d}")
                print(bar, least, "  ".join(cells))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
