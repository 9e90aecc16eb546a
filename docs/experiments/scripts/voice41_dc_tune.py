"""Round voice41, tuning data only: a microphone's DC offset, and the stream's high-pass that takes it out.

Round voice37's tuning clips (`voice37_tune.tune_items`: 40 of each command and 200 other words, train seed 12's tune
splits), each at a peak level in a quiet room's hiss (-70 dBFS) through a 48 kHz microphone's path (`through_mic`),
with `--dc` added to what the microphone hands over, fed to the service's segmenter with the high-pass at `--highpass`
Hz (or off) and the default engine: commands heard, other words taken, words no segment covered.

    .venv/bin/python docs/experiments/scripts/voice41_dc_tune.py --dc 0,0.03 --highpass off
    .venv/bin/python docs/experiments/scripts/voice41_dc_tune.py --dc 0,0.03 --highpass 30
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402

from bench.voice_bench import Policy, early_look_arg  # noqa: E402
from bench.voice_levels import at_level, in_room, through_mic  # noqa: E402
from bench.voice_walking import run_streams  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--dc", default="0,0.03", help="DC offsets, fractions of full scale")
    ap.add_argument("--peaks", default="-38,-26")
    ap.add_argument("--highpass", type=early_look_arg, default=SegmenterConfig.highpass_hz, help="Hz, or off")
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    config = SegmenterConfig(highpass_hz=args.highpass, highpass_dc_share=0.0)  # the switch before round voice43
    for dc in (float(v) for v in args.dc.split(",")):
        for peak in (float(v) for v in args.peaks.split(",")):
            def build(speech: np.ndarray, rng: np.random.Generator, peak: float = peak, dc: float = dc) -> np.ndarray:
                return through_mic(in_room(at_level(speech, peak), -70.0, rng), 48000) + dc

            row = run_streams(engine, items, build, config, policy, 37)
            print(json.dumps({"highpass_hz": args.highpass, "dc": dc, "peak_dbfs": peak,
                              **{k: row[k] for k in ("command_accuracy", "oov_accepted", "false_walks",
                                                     "no_segment_over_word", "segments_per_clip")}}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
