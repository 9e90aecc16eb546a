"""Stop 83, tuning data only: does loud speech alone switch the high-pass on, in a stream with no DC offset?

`SegmenterConfig.highpass_from_dbfs` switches the high-pass on once the mean of the stream's last `noise_floor_s`
outside utterances is -50 dBFS (about 100 of 32,768) or more from zero. Round 37's 280 tune commands and 200 other
words, each 1.2 s into its own stream in a quiet room's -70 dBFS hiss (seed 37), through a 48 kHz microphone's path,
no offset, fed to the segmenter as it was at stop 83 (`highpass_dc_share` 0: the mean alone; round voice43 added
the share): at each peak level, how many streams switched it on, and when (stream seconds) and at what mean (LSB),
for the first few.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice42_switch_probe.py --cache /tmp/s83/tune.pickle
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

from bench.voice_walking import CHUNK, rounded_pcm  # noqa: E402
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--peaks", default="-3,-14,-26")
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    for peak in map(float, args.peaks.split(",")):
        rng = np.random.default_rng(37)
        switched: list[tuple[int, float, int]] = []
        for i, it in enumerate(items):
            speech = np.frombuffer(it.pcm, "<i2") / 32768.0
            pcm = rounded_pcm(np.clip(tuning_stream(speech, peak, rng), -1.0, 1.0))
            seg = Segmenter(SegmenterConfig(highpass_dc_share=0.0))  # the switch as it was at stop 83
            for k in range(0, len(pcm), CHUNK):
                seg.feed(pcm[k : k + CHUNK])
                if seg._offset_on:
                    mean = sum(v for v, *_ in seg._offset) / max(1, sum(n for *_, n in seg._offset))
                    switched.append((i, round((k + CHUNK) / SAMPLE_WIDTH / SAMPLE_RATE, 2), round(mean)))
                    break
        print(f"{peak:+.0f} dBFS: switched on in {len(switched)} of {len(items)} streams; first (item, s, mean LSB): "
              f"{switched[:8]}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
