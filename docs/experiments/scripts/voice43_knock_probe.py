"""Round voice43, after its decision (reported, not judged): the switch's two rules on held-out words with a knock.

Held-out seed 2281's clips never switched the high-pass on with no offset under either rule, so the round's runs could
not show what the change is for. Here each of that seed's picked clips (`--per-family 14`: 133 commands, 182 other
words) is `voice_levels`' stream at `--peak` dBFS in a quiet room's hiss, through a 48 kHz microphone's path, with a
knock on the robot `--knock-s` before the word: a half sine 20-80 ms long, 0.05-0.3 of full scale, either way up
(drawn per stream). Fed to the service's segmenter and the default engine with the switch on the mean alone (share 0,
the rule before round voice43) and with the default share; prints commands heard, other words taken, false walks,
streams switched, and the commands one heard and the other did not.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice43_knock_probe.py --peak -26
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import Policy, heldout_items  # noqa: E402
from bench.voice_levels import at_level, in_room, through_mic  # noqa: E402
from bench.voice_walking import LEAD_S, paired, pick, run_streams  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=2281)
    ap.add_argument("--peak", type=float, default=-26.0)
    ap.add_argument("--knock-s", type=float, default=0.4)
    args = ap.parse_args()
    clips = pick(heldout_items(args.seed, 2), 14, args.seed)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()

    def build(speech: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        x = in_room(at_level(speech, args.peak), -70.0, rng)
        n = int(rng.uniform(0.02, 0.08) * SAMPLE_RATE)
        at = int((LEAD_S - args.knock_s) * SAMPLE_RATE)
        x[at : at + n] += rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.3) * np.sin(np.pi * np.arange(n) / n)
        return through_mic(x, 48000)

    heard: dict[float, str] = {}
    for share in (0.0, SegmenterConfig.highpass_dc_share):
        row = run_streams(engine, clips, build, SegmenterConfig(highpass_dc_share=share), policy, args.seed)
        heard[share] = str(row["commands_heard_each"])
        print(f"share {share:g}: commands heard {heard[share].count('1')}/{len(heard[share])}, other words taken "
              f"{str(row['others_taken_each']).count('1')}/{row['n']['oov']}, false walks {row['false_walks']}, "
              f"streams switched {row['highpass_switched_on']}", flush=True)
    lost, gained = paired(heard[0.0], heard[SegmenterConfig.highpass_dc_share])
    print(f"share 0 -> {SegmenterConfig.highpass_dc_share:g}: commands lost {lost}, gained {gained}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
