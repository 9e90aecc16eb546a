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

from voice37_tune import tune_items, tuning_stream  # noqa: E402

from bench.voice_bench import Item, Policy  # noqa: E402
from bench.voice_walking import paired, run_streams  # noqa: E402
from services.voice.engine import Engine, make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402

CASES = {"clean": (0.0, None, 37), "clean_twin": (0.0, None, 1037), "latched": (0.03, 30.0, 37),
         "latched_twin": (0.03, 30.0, 1037)}  # name: (offset, high-pass Hz, hiss seed)
PAIRS = [("clean", "clean_twin"), ("clean", "latched"), ("clean_twin", "latched_twin"), ("latched", "latched_twin")]


def hear(items: list[Item], engine: Engine, policy: Policy, peak: float, dc: float, config: SegmenterConfig,
         seed: int) -> tuple[list[bool], int]:
    """Each item in its own stream at `peak` dBFS in -70 dBFS hiss (drawn from `seed`), through a 48 kHz
    microphone's path, plus `dc` (of full scale) (`voice_walking.run_streams`): for each command whether it was heard,
    and how many other words were taken for commands."""

    def build(speech: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return tuning_stream(speech, peak, rng, dc)

    row = run_streams(engine, items, build, config, policy, seed)
    return [c == "1" for c in str(row["commands_heard_each"])], str(row["others_taken_each"]).count("1")


def compare(heard: dict[str, list[bool]], pairs: list[tuple[str, str]]) -> None:
    """For each pair of cases, the commands the first heard and the second did not (lost), and the reverse."""
    for a, b in pairs:
        lost, gained = paired("".join("01"[x] for x in heard[a]), "".join("01"[x] for x in heard[b]))
        print(f"{a} -> {b}: commands lost {lost}, gained {gained}", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--peak", type=float, default=-3.0)
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    heard: dict[str, list[bool]] = {}
    for name, (dc, hz, seed) in CASES.items():
        config = SegmenterConfig(highpass_hz=hz, highpass_dc_share=0.0)  # the switch as it was before round voice43
        heard[name], taken = hear(items, engine, policy, args.peak, dc, config, seed)
        print(f"{name:13} commands heard {sum(heard[name])}/{len(heard[name])}, other words taken {taken}", flush=True)
    compare(heard, PAIRS)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
