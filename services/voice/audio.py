"""Audio helpers: the one format every engine takes (16 kHz, 16-bit, mono PCM) and WAV reading."""

from __future__ import annotations

import wave
from pathlib import Path

import numpy as np

SAMPLE_RATE = 16_000
"""Every engine here decodes 16 kHz, 16-bit, mono PCM."""

SAMPLE_WIDTH = 2


class AudioError(ValueError):
    """Audio that cannot be used: not a WAV file, wrong rate, width or channel count."""


def read_wav(path: Path | str) -> bytes:
    """The PCM frames of a 16 kHz, 16-bit, mono WAV file; `AudioError` says what is wrong otherwise."""
    path = Path(path)
    try:
        with wave.open(str(path), "rb") as w:
            rate, width, channels = w.getframerate(), w.getsampwidth(), w.getnchannels()
            frames = w.readframes(w.getnframes())
    except FileNotFoundError:
        raise AudioError(f"{path}: no such file") from None
    except (wave.Error, EOFError) as exc:
        raise AudioError(f"{path}: not a PCM WAV file ({exc})") from None
    if (rate, width, channels) != (SAMPLE_RATE, SAMPLE_WIDTH, 1):
        raise AudioError(
            f"{path}: {rate} Hz, {8 * width}-bit, {channels} channel(s); need 16000 Hz, 16-bit, mono "
            f"(convert with: sox IN.wav -r 16000 -b 16 -c 1 OUT.wav)"
        )
    return frames


def write_wav(path: Path | str, pcm: bytes) -> None:
    """Write 16 kHz, 16-bit, mono PCM as a WAV file."""
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(SAMPLE_WIDTH)
        w.setframerate(SAMPLE_RATE)
        w.writeframes(pcm)


def duration_s(pcm: bytes) -> float:
    return len(pcm) / (SAMPLE_RATE * SAMPLE_WIDTH)


def to_pcm(samples: np.ndarray) -> bytes:
    """Float samples in [-1, 1] to 16-bit PCM bytes (clipped): the generator's conversion, scaled by 32767 and truncated
    toward zero. The training clips (and so the committed models) and the tests' chosen clips are its exact output, so
    it stays; it is not what a microphone hands over (`rounded_pcm`)."""
    return (np.clip(samples, -1.0, 1.0) * 32767.0).astype("<i2").tobytes()


def rounded_pcm(samples: np.ndarray) -> bytes:
    """Float samples in [-1, 1] (a 16-bit value / 32768, as `from_pcm` gives them) to 16-bit PCM bytes as a sound
    card's converter and the service's microphone path (`mic.py`) make them: each rounded to the nearest step, clipped;
    `from_pcm` then `rounded_pcm` gives the same bytes back. The benches hand their streams over with it. With
    `to_pcm` instead (until stop 81) every sample shrank by a step toward zero, so a -70 dBFS hiss lost 0.7 dB more than
    the speech over it and the far-voice rows were flattered (voice README, round voice41c)."""
    x = np.rint(np.asarray(samples, dtype=np.float64) * 32768.0)
    return np.clip(x, -32768, 32767).astype("<i2").tobytes()


def from_pcm(pcm: bytes) -> np.ndarray:
    """16-bit PCM bytes to float samples in [-1, 1]."""
    return np.frombuffer(pcm, dtype="<i2").astype(np.float32) / 32768.0


def dither(pcm: bytes, lsb: float = 2.0, seed: int = 0) -> bytes:
    """Add a few LSB of noise: runs of exact zeros hurt pocketsphinx's feature normalisation."""
    x = np.frombuffer(pcm, dtype="<i2").astype(np.float32)
    x += np.random.default_rng(seed).normal(0.0, lsb, x.shape).astype(np.float32)
    return np.clip(x, -32768, 32767).astype("<i2").tobytes()
