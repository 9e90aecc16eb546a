"""Round voice43, tuning data only: what share of the power outside utterances does the mean carry, when loud speech
with no offset leaves a mean that `highpass_from_dbfs` takes for one, and when a real offset is there?

Round 37's 280 tune commands and 200 other words, each 1.2 s into its own stream in a quiet room's -70 dBFS hiss
(seed 37), through a 48 kHz microphone's path with an offset `dc` added, fed to a segmenter whose high-pass never
switches (`highpass_dc_share` 2). At every chunk where the switch's other conditions hold (half of `noise_floor_s`
heard outside utterances, the mean at `highpass_from_dbfs` or further), the mean's share of the power
(`Segmenter.offset_seen_so_far`). Per peak level and offset: how many streams reach the mean's level at all, the
largest share each reaches (quantiles over streams), and how many would switch at each candidate share, with the
median time of the first switch (stream seconds).

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice43_share_probe.py --cache /tmp/s84/tune.pickle
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

CANDIDATES = (0.25, 0.5, 0.75)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, required=True)
    ap.add_argument("--peaks", default="-3,-14,-26,-44")
    ap.add_argument("--dcs", default="0,0.005,0.03")
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    config = SegmenterConfig(highpass_dc_share=2.0)
    threshold = 10 ** (config.highpass_from_dbfs / 20) if config.highpass_from_dbfs is not None else 0.0
    window = config.noise_floor_s * SAMPLE_RATE
    for dc in map(float, args.dcs.split(",")):
        for peak in map(float, args.peaks.split(",")):
            rng = np.random.default_rng(37)
            best: list[float] = []  # per stream that reaches the mean's level: the largest share
            first: dict[float, list[float]] = {c: [] for c in CANDIDATES}  # per candidate: first switch times
            for it in items:
                speech = np.frombuffer(it.pcm, "<i2") / 32768.0
                x = tuning_stream(speech, peak, rng, dc)
                pcm = rounded_pcm(np.clip(x, -1.0, 1.0))
                seg = Segmenter(config)
                shares: list[tuple[float, float]] = []  # (stream s, share) where the other conditions hold
                for k in range(0, len(pcm), CHUNK):
                    last = seg._offset[-1] if seg._offset else None
                    seg.feed(pcm[k : k + CHUNK])
                    total, mean, share = seg.offset_seen_so_far()
                    heard_outside = bool(seg._offset) and seg._offset[-1] is not last  # this chunk was kept
                    if heard_outside and total >= window / 2 and mean >= threshold:
                        shares.append(((k + CHUNK) / SAMPLE_WIDTH / SAMPLE_RATE, share))
                if shares:
                    best.append(max(s for _, s in shares))
                    for c in CANDIDATES:
                        t = next((t for t, s in shares if s >= c), None)
                        if t is not None:
                            first[c].append(t)
            q = np.quantile(best, [0.0, 0.5, 0.9, 1.0]).round(3).tolist() if best else []
            print(f"dc {dc:g}, {peak:+.0f} dBFS: {len(best)} of {len(items)} streams reach the mean; largest share "
                  f"min/median/p90/max {q}; would switch at share "
                  + ", ".join(f"{c}: {len(first[c])} (median {np.median(first[c]) if first[c] else float('nan'):.2f} s)"
                              for c in CANDIDATES), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
