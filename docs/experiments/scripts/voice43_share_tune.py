"""Round voice43, tuning data only: the high-pass's switch with and without `highpass_dc_share`, word for word.

Round 37's 280 tune commands and 200 other words (`voice37_tune.tune_items`), through a 48 kHz microphone's path, fed
to the service's segmenter and the default engine, each in its own stream either in a quiet room (`--peak` dBFS in
-70 dBFS hiss, seed 37, `voice41e_twin_probe.hear`) or in a walking robot's modelled noise (`--snr` dB under the
speech, `voice_walking.run_ratio`), with the microphone's offset `--dc`; once with the switch on the mean alone
(share 0, the rule before round voice43) and once with `--share`. Prints each case's commands heard, other words taken
and false walks, and the commands one heard and the other did not.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice43_share_tune.py --cache /tmp/s84/tune.pickle \\
        --peak -3 --dc 0
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice43_share_tune.py --cache /tmp/s84/tune.pickle \\
        --snr 10 --dc 0.03
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402
from voice41e_twin_probe import hear  # noqa: E402

from bench.ego_noise import EgoNoiseModel  # noqa: E402
from bench.voice_bench import Policy  # noqa: E402
from bench.voice_walking import noise_source, paired, run_ratio  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, required=True)
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--peak", type=float, help="a quiet room, the speech's peak (dBFS)")
    where.add_argument("--snr", type=float, help="a walking robot, the speech over its noise (dB)")
    ap.add_argument("--dc", type=float, default=0.0)
    ap.add_argument("--share", type=float, default=0.75)
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    model = EgoNoiseModel()
    heard: dict[float, str] = {}
    for share in (0.0, args.share):
        config = SegmenterConfig(highpass_dc_share=share)
        if args.peak is not None:
            each, taken = hear(items, engine, policy, args.peak, args.dc, config, 37)
            heard[share], walks = "".join("01"[x] for x in each), None
        else:
            row = run_ratio(engine, items, args.snr, config, policy, 37,
                            lambda s, rng: noise_source(s, rng, None, model), 48000, args.dc)
            heard[share], taken, walks = (str(row["commands_heard_each"]), str(row["others_taken_each"]).count("1"),
                                          row["false_walks"])
        print(f"share {share:g}: commands heard {heard[share].count('1')}/{len(heard[share])}, other words taken "
              f"{taken}, false walks {walks}", flush=True)
    lost, gained = paired(heard[0.0], heard[args.share])
    print(f"share 0 -> {args.share:g}: commands lost {lost}, gained {gained}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
