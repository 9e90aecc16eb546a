"""Word streams for the segmenter's tests: espeak-ng words in a faint hiss (or louder noise), fed in 30 ms chunks."""

from __future__ import annotations

import numpy as np

from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.engine import Recognition
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig

LEAD_S = 1.0
STEP = 960  # 30 ms chunks, as the service's sources


def word_stream(*words: str, gap_s: float = 0.8, noise_db: float | None = None) -> bytes:
    """The words (espeak-ng en-us) one after another, `gap_s` from one word's end to the next, in a faint hiss,
    or with `noise_db` in white noise that many dB under the words' speech."""
    parts = [np.zeros(int(LEAD_S * SAMPLE_RATE))]
    for word in words:
        speech = np.frombuffer(read_wav(synth.speech_clip(word, "en-us", 150).path), "<i2") / 32768.0
        loud = np.flatnonzero(np.abs(speech) > 0.02 * np.abs(speech).max())  # without the silence around it
        parts += [speech[loud[0] : loud[-1] + 1], np.zeros(int(gap_s * SAMPLE_RATE))]
    x = np.concatenate([*parts, np.zeros(SAMPLE_RATE)])
    rng = np.random.default_rng(1)
    if noise_db is None:
        return to_pcm(x + rng.normal(0, 3e-4, x.size))
    speech_rms = np.sqrt(np.mean(x[np.abs(x) > 0.05 * np.abs(x).max()] ** 2))
    return to_pcm(np.clip(x + rng.normal(0, speech_rms / 10 ** (noise_db / 20), x.size), -1, 1))


class Judge:
    """A recogniser that records what it was asked and answers as told."""

    def __init__(self, command: object | None, confidence: float = 0.9) -> None:
        self.command, self.confidence, self.calls = command, confidence, 0

    def __call__(self, pcm: bytes) -> Recognition:
        self.calls += 1
        return Recognition(self.command, self.command.value if self.command else "other",  # type: ignore[attr-defined]
                           self.confidence, "test")


def emitted(pcm: bytes, config: SegmenterConfig, judge: Judge | None = None) -> list[tuple[float, Segment]]:
    """(stream time at which the segment was emitted, the segment)."""
    seg = Segmenter(config, recognise=judge)
    out = []
    for k in range(0, len(pcm), STEP):
        out += [((k + STEP) / 2 / SAMPLE_RATE, s) for s in seg.feed(pcm[k : k + STEP])]
    return out
