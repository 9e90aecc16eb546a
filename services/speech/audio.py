"""Facts about a WAV file: duration, loudness and how much of it is sound rather than silence."""

from __future__ import annotations

import wave
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt


class AudioError(ValueError):
    """A file is not a WAV this service can read (16-bit PCM)."""


@dataclass(frozen=True)
class WavInfo:
    path: Path
    sample_rate: int
    frames: int
    duration_s: float
    rms: float
    """Root mean square of the samples, 0..1 of full scale."""
    active_fraction: float
    """Share of 20 ms windows louder than -40 dBFS RMS: near 0 for silence, roughly 0.5..0.9 for speech."""


def read_samples(path: Path) -> tuple[npt.NDArray[np.float64], int]:
    """Mono samples scaled to -1..1, and the sample rate."""
    try:
        with wave.open(str(path), "rb") as w:
            if w.getsampwidth() != 2:
                raise AudioError(f"{path}: {8 * w.getsampwidth()}-bit samples, expected 16-bit PCM")
            rate, channels = w.getframerate(), w.getnchannels()
            raw = w.readframes(w.getnframes())
    except (wave.Error, EOFError) as exc:
        raise AudioError(f"{path}: not a readable WAV file ({exc})") from None
    samples = np.frombuffer(raw, dtype="<i2").astype(np.float64) / 32768.0
    if channels > 1:
        samples = samples.reshape(-1, channels).mean(axis=1)
    return samples, rate


def wav_info(path: Path) -> WavInfo:
    samples, rate = read_samples(path)
    window = max(1, int(rate * 0.02))
    n = len(samples) // window
    if n:
        frames = samples[: n * window].reshape(n, window)
        active = float(np.mean(np.sqrt(np.mean(frames**2, axis=1)) > 0.01))
    else:
        active = 0.0
    rms = float(np.sqrt(np.mean(samples**2))) if len(samples) else 0.0
    return WavInfo(
        path=path,
        sample_rate=rate,
        frames=len(samples),
        duration_s=len(samples) / rate if rate else 0.0,
        rms=rms,
        active_fraction=active,
    )


def wav_duration(path: Path) -> float:
    """Duration in seconds from the header alone (cheap: used on every utterance)."""
    try:
        with wave.open(str(path), "rb") as w:
            rate = w.getframerate()
            return w.getnframes() / rate if rate else 0.0
    except (wave.Error, EOFError) as exc:
        raise AudioError(f"{path}: not a readable WAV file ({exc})") from None
