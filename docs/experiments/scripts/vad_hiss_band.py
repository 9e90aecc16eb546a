"""Stop 71, measured: does the live stream's VAD (Silero) find quiet speech as well when the room's hiss has no energy
near 8 kHz, as a real microphone's does (its converter's anti-alias filter, or the service's resampler for a 44.1 or
48 kHz microphone)?

Held-out seed 7183's clips (`voice_walking.pick`, 4 per family; the first 80), each at a -38 dBFS peak 1.2 s into
white hiss at -70 dBFS RMS (`voice_levels.in_room`), fed to the service's segmenter in 30 ms chunks. Counted: clips in
which the segmenter found any segment, for the stream as generated; through a 48 kHz microphone and the service's
resampler (`voice_levels.through_mic`); the whole stream low-passed at 7.2 kHz; and only the hiss low-passed at
7.2 kHz, brought back to the same RMS (the speech as generated).

    .venv/bin/python docs/experiments/scripts/vad_hiss_band.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.signal import butter, sosfiltfilt

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import Item, heldout_items  # noqa: E402,F401  (Item: the clip cache's pickled class)
from bench.voice_levels import at_level, in_room, through_mic  # noqa: E402
from bench.voice_walking import LEAD_S, pick  # noqa: E402
from services.voice.audio import SAMPLE_RATE, to_pcm  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402


def found(x: np.ndarray) -> bool:
    """Whether the service's segmenter finds any segment in `x`."""
    seg, pcm = Segmenter(SegmenterConfig()), to_pcm(np.clip(x, -1.0, 1.0))
    return any(seg.feed(pcm[k : k + 960]) for k in range(0, len(pcm), 960)) or bool(seg.flush())


def main() -> int:
    clips = pick(heldout_items(7183, 1), 4, 7183)[:80]
    rng = np.random.default_rng(1)
    low = butter(10, 7200, fs=SAMPLE_RATE, output="sos")
    counts = {"as generated": 0, "a 48 kHz microphone, resampled": 0, "all low-passed at 7.2 kHz": 0,
              "the hiss alone low-passed at 7.2 kHz": 0}
    for it in clips:
        speech = at_level(np.frombuffer(it.pcm, "<i2") / 32768.0, -38.0)
        x = in_room(speech, -70.0, rng)
        counts["as generated"] += found(x)
        counts["a 48 kHz microphone, resampled"] += found(through_mic(x, 48000))
        counts["all low-passed at 7.2 kHz"] += found(sosfiltfilt(low, x))
        hiss = in_room(np.zeros_like(speech), -70.0, rng)
        shaped = sosfiltfilt(low, hiss)
        shaped *= np.sqrt(np.mean(hiss**2) / np.mean(shaped**2))
        at = int(LEAD_S * SAMPLE_RATE)
        shaped[at : at + speech.size] += speech
        counts["the hiss alone low-passed at 7.2 kHz"] += found(shaped)
    for name, n in counts.items():
        print(f"{name:40} speech found in {n} of {len(clips)} clips")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
