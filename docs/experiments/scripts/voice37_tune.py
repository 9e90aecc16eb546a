"""Round voice37, tuning data only: Silero hears a quiet live stream lifted to a level (`SegmenterConfig.vad_lift_dbfs`).

`bench/voice_levels.py`'s stream path on tuning clips instead of held-out ones: round voice36's cache of the `tune` and
`neighbours-tune` splits (train seed 12), 40 commands of each word and 200 other words drawn with a fixed seed, each
scaled to a peak level and placed in a quiet room's hiss (-70 dBFS), fed to the service's segmenter and the default
engine. Each `SegmenterConfig.vad_lift_dbfs` (none: today's) at each level; then the hiss alone for 60 s
(segments and commands heard in it).

    .venv/bin/python docs/experiments/scripts/voice37_tune.py --floors none,-20 --json /tmp/s70/voice37_tune.json
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.ego_noise import EgoNoiseModel  # noqa: E402
from bench.voice_bench import OTHER, Item, Policy  # noqa: E402
from bench.voice_levels import at_level, in_room, levels, through_mic  # noqa: E402
from bench.voice_walking import noise_source, run_ratio, run_streams, stream  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def tuning_stream(speech: np.ndarray, peak: float, rng: np.random.Generator, dc: float = 0.0,
                  mic_rate: int | None = 48000) -> np.ndarray:
    """One tuning word (float, ±1) as the probes hear it: at `peak` dBFS, `LEAD_S` into a quiet room's -70 dBFS hiss
    (drawn from `rng`), through a microphone at `mic_rate` (None: 16 kHz as it is), plus its DC offset `dc`."""
    return through_mic(in_room(at_level(speech, peak), -70.0, rng), mic_rate) + dc


def tune_items(cache: Path, per_command: int, others: int, seed: int) -> list[Item]:
    """Round voice36's tune clips (rendered by its script into `cache` when missing), `per_command` of each command and
    `others` other words."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from voice36_tune import clips as voice36_clips

    clips = voice36_clips(12, 2, cache)
    rng = np.random.default_rng(seed)
    out: list[Item] = []
    for label in sorted({c[0] for c in clips}):
        pool = [c for c in clips if c[0] == label]
        take = rng.permutation(len(pool))[: per_command if label < OTHER else others]
        out += [Item("tune", "", pool[i][0], pool[i][1], "tune", pool[i][2]) for i in sorted(take)]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s70/voice36_tune_clips.pickle"))
    ap.add_argument("--floors", default="none,-20", help="SegmenterConfig.vad_lift_dbfs values (none: today's)")
    ap.add_argument("--peaks", default="-50,-44,-38,-32,-26,-14,-3")
    ap.add_argument("--per-command", type=int, default=40)
    ap.add_argument("--others", type=int, default=200)
    ap.add_argument("--seed", type=int, default=37)
    ap.add_argument("--hiss-s", type=float, default=60.0)
    ap.add_argument("--lift-floor", type=float, help="SegmenterConfig.vad_lift_floor_dbfs (round voice37b)")
    ap.add_argument("--walking", default="", help="also these speech-to-walking-noise ratios (dB), clips as rendered")
    ap.add_argument("--mic-rate", type=int, help="the quiet room's streams through a microphone at this rate and the "
                                                   "service's resampler (`voice_levels.through_mic`; stop 71)")
    ap.add_argument("--second", action="store_true", help="SegmenterConfig.vad_lift_second (round voice37c): a second "
                                                            "VAD hears the lifted stream")
    ap.add_argument("--hold", type=float, default=0.0, help="SegmenterConfig.vad_lift_hold_s (round voice37d)")
    ap.add_argument("--head", help="spotter head file (round voice39; default: the committed default head)")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    items = tune_items(args.cache, args.per_command, args.others, args.seed)
    print(f"{sum(i.label < OTHER for i in items)} commands, {sum(i.label == OTHER for i in items)} other words", flush=True)
    policy = Policy.from_knowledge()
    engine = make_engine("spotter", head_path=args.head)
    rows = []
    for floor in args.floors.split(","):
        config = replace(SegmenterConfig(), vad_lift_dbfs=None if floor == "none" else float(floor),
                         vad_lift_floor_dbfs=args.lift_floor, vad_lift_second=args.second,
                         vad_lift_hold_s=args.hold)
        for snr in (float(v) for v in args.walking.split(",") if v):
            row = {"floor": floor, "lift_floor": args.lift_floor, "walking_snr_db": snr,
                   **run_ratio(engine, items, snr, config, policy, args.seed,
                               lambda seconds, rng: noise_source(seconds, rng, None, EgoNoiseModel()))}
            rows.append(row)
            print(json.dumps({k: row[k] for k in ("floor", "lift_floor", "walking_snr_db", "command_accuracy",
                                                  "oov_accepted", "false_walks", "no_segment_over_word",
                                                  "end_of_speech_to_segment_ms_p50_p90")}), flush=True)
        for peak in levels(args.peaks, ""):
            def build(speech: np.ndarray, rng: np.random.Generator, peak: float = peak) -> np.ndarray:
                return tuning_stream(speech, peak, rng, mic_rate=args.mic_rate)

            row = {"floor": floor, "lift_floor": args.lift_floor, "mic_rate": args.mic_rate, "peak_dbfs": peak, **run_streams(engine, items, build, config, policy, args.seed)}
            rows.append(row)
            print(json.dumps({k: row[k] for k in ("floor", "peak_dbfs", "command_accuracy", "oov_accepted",
                                                  "false_walks", "no_segment_over_word", "segments_per_clip",
                                                  "end_of_speech_to_segment_ms_p50_p90")}), flush=True)
        hiss = through_mic(np.random.default_rng(args.seed).normal(0.0, 10 ** (-70 / 20), int(args.hiss_s * SAMPLE_RATE)),
                           args.mic_rate)
        segs = stream(engine, hiss, config)
        alone = {"floor": floor, "hiss_alone_s": args.hiss_s, "segments": len(segs),
                 "commands": [s[3].value for s in segs if s[3] is not None and policy.takes(s[3], s[4])]}
        rows.append(alone)
        print(json.dumps(alone), flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
