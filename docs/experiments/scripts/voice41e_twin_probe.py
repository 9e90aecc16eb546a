"""Round voice41e, tuning data only: how far a row moves by chance, word for word.

Round voice37's tuning clips (`voice37_tune.tune_items`: 40 of each command and 200 other words), each 1.2 s into its
own stream at `--peak` in a quiet room's hiss (-70 dBFS), through a 48 kHz microphone's path, fed to the service's
segmenter and the default engine, four ways: the clean microphone (hiss seed 37), its twin (the same words in another
draw of the same hiss, seed 1037), and the high-pass latched on over an offset of 0.03 of full scale (round 41c's
candidate), with each hiss. Prints each case's commands heard and other words taken, then, for pairs of cases, how
many commands one heard and the other did not (lost) and the reverse (gained).

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice41e_twin_probe.py --peak -3
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402

from bench.voice_bench import Policy  # noqa: E402
from bench.voice_levels import at_level, in_room, through_mic  # noqa: E402
from bench.voice_walking import LEAD_S, OTHER, WORDS, stream  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402

CASES = {"clean": (0.0, None, 37), "clean_twin": (0.0, None, 1037), "latched": (0.03, 30.0, 37),
         "latched_twin": (0.03, 30.0, 1037)}  # name: (offset, high-pass Hz, hiss seed)
PAIRS = [("clean", "clean_twin"), ("clean", "latched"), ("clean_twin", "latched_twin"), ("latched", "latched_twin")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--peak", type=float, default=-3.0)
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    heard: dict[str, list[bool]] = {}
    for name, (dc, hz, seed) in CASES.items():
        rng = np.random.default_rng(seed)
        config = SegmenterConfig(highpass_hz=hz)
        heard[name] = []
        taken = 0
        for it in items:
            speech = np.frombuffer(it.pcm, "<i2") / 32768.0
            x = np.clip(through_mic(in_room(at_level(speech, args.peak), -70.0, rng), 48000) + dc, -1.0, 1.0)
            start, end = LEAD_S, LEAD_S + speech.size / SAMPLE_RATE
            over = [s for s in stream(engine, x, config) if s[1] < end and s[2] > start]
            cmd, conf = next(((c, f) for _, _, _, c, f in over if c is not None), (None, 0.0))
            if it.label < OTHER:
                heard[name].append(cmd is not None and cmd.value == WORDS[it.label] and policy.takes(cmd, conf) is not None)
            else:
                taken += policy.takes(cmd, conf) is not None
        print(f"{name:13} commands heard {sum(heard[name])}/{len(heard[name])}, other words taken {taken}", flush=True)
    for a, b in PAIRS:
        lost = sum(x and not y for x, y in zip(heard[a], heard[b], strict=True))
        gained = sum(y and not x for x, y in zip(heard[a], heard[b], strict=True))
        print(f"{a} -> {b}: commands lost {lost}, gained {gained}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
