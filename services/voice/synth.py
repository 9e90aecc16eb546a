"""A synthetic speech set made with espeak-ng: commands, confusable non-commands and pure noise.

Voices and speeds are split into a *tune* set (used to choose thresholds) and a *held-out* set
(used only to measure); the non-command words are split the same way, so the benchmark measures
rejection on words the thresholds never saw. Clips are 16 kHz mono WAV with dithered silence
around the speech, optionally mixed with white or pink noise at a given SNR. They are cached under
`$HRI_VOICE_CACHE` (default: `<tmp>/hri-voice-synth`), keyed by everything that shapes them, so
a second run costs nothing. Nothing here is committed to the repository.
"""

from __future__ import annotations

import hashlib
import io
import os
import shutil
import subprocess
import tempfile
import wave
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from math import gcd
from pathlib import Path
from typing import Literal

import numpy as np
from scipy.signal import resample_poly

from schemas.messages import Command
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm, write_wav

SYNTH_VERSION = 1
"""Bump when the clip recipe changes, so stale cached clips are not reused."""

Kind = Literal["command", "oov", "noise"]
Split = Literal["tune", "heldout"]

COMMAND_WORDS: tuple[str, ...] = tuple(c.value for c in Command)

# Confusable non-commands: near rhymes and shared onsets/vowels of the six commands, and the
# issue's examples. "know" is left out on purpose: it is "no" in the pocketsphinx dictionary.
OOV_TUNE: tuple[str, ...] = (
    "table", "going", "toast", "dog", "stone", "hello", "sand", "yellow", "goat", "cold",
    "show", "stay", "top", "shop", "town", "yet", "now", "good", "ghost", "oh", "grow",
    "stamp", "sound", "chess", "window", "robot", "coffee", "what time is it", "okay then",
)
OOV_HELDOUT: tuple[str, ...] = (
    "gold", "code", "snow", "slow", "low", "step", "stack", "desk", "band", "gown", "guess",
    "note", "nose", "new", "gun", "book", "goal", "ago", "glow", "store", "start", "hand",
    "less", "boat", "water", "banana", "hello robot", "good morning", "thank you",
)

# espeak-ng voice specs (language+variant) and speeds (words per minute).
VOICES_TUNE: tuple[str, ...] = ("en-us", "en-gb+f3", "en-us+m3", "en-gb-x-rp+f2")
VOICES_HELDOUT: tuple[str, ...] = ("en-gb-scotland+m4", "en-us+f4", "en-029+m7", "en-us-nyc+f5", "en-gb+m2")
SPEEDS_TUNE: tuple[int, ...] = (140, 180)
SPEEDS_HELDOUT: tuple[int, ...] = (125, 160, 195)
SNRS_DB: tuple[float | None, ...] = (None, 20.0, 10.0)
"""Speech-to-noise ratios mixed in; None is clean (dither only)."""

NOISES: tuple[str, ...] = ("white", "pink", "brown", "hum", "clicks")
NOISE_LEVELS_DBFS: tuple[float, ...] = (-40.0, -26.0, -14.0)

PAD_S = 0.4
DITHER_LSB = 2.0


class SynthError(RuntimeError):
    """espeak-ng is missing or failed."""


@dataclass(frozen=True)
class Clip:
    """One synthetic recording: what was said (or which noise), how, and where the WAV is."""

    path: Path
    kind: Kind
    text: str
    voice: str = ""
    speed: int = 0
    snr_db: float | None = None

    @property
    def expected(self) -> Command | None:
        """The command a perfect recogniser would report (None for non-commands and noise)."""
        return Command(self.text) if self.kind == "command" else None


def cache_dir() -> Path:
    root = os.environ.get("HRI_VOICE_CACHE") or str(Path(tempfile.gettempdir()) / "hri-voice-synth")
    path = Path(root)
    path.mkdir(parents=True, exist_ok=True)
    return path


def espeak_available() -> bool:
    return shutil.which("espeak-ng") is not None


def speak(text: str, voice: str = "en-us", speed: int = 160) -> np.ndarray:
    """espeak-ng's rendering of `text` as float samples at 16 kHz (no padding)."""
    exe = shutil.which("espeak-ng")
    if exe is None:
        raise SynthError("espeak-ng is not installed (apt-get install espeak-ng)")
    try:
        out = subprocess.run(
            [exe, "-v", voice, "-s", str(speed), "--stdout", text],
            capture_output=True, check=True, timeout=30,
        ).stdout
    except subprocess.CalledProcessError as exc:
        raise SynthError(f"espeak-ng failed for voice {voice!r}: {exc.stderr.decode(errors='replace')}") from None
    with wave.open(io.BytesIO(out), "rb") as w:
        rate = w.getframerate()
        x = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(np.float64) / 32768.0
    g = gcd(SAMPLE_RATE, rate)
    return resample_poly(x, SAMPLE_RATE // g, rate // g)


def noise(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Unit-RMS noise of a named colour or kind."""
    if kind == "white":
        x = rng.normal(size=n)
    elif kind in ("pink", "brown"):
        spec = np.fft.rfft(rng.normal(size=n))
        f = np.arange(spec.size, dtype=np.float64)
        f[0] = 1.0
        spec /= np.sqrt(f) if kind == "pink" else f
        x = np.fft.irfft(spec, n)
    elif kind == "hum":
        t = np.arange(n) / SAMPLE_RATE
        x = sum(np.sin(2 * np.pi * 50 * k * t + rng.uniform(0, 6.3)) / k for k in (1, 2, 3, 5))
        x = x + 0.05 * rng.normal(size=n)
    elif kind == "clicks":
        x = 0.01 * rng.normal(size=n)
        for at in rng.integers(0, n - 200, size=max(1, n // 4000)):
            x[at : at + 200] += rng.normal(size=200) * np.exp(-np.arange(200) / 30.0) * 8.0
    else:
        raise ValueError(f"unknown noise {kind!r}: one of {', '.join(NOISES)}")
    return x / (np.sqrt(np.mean(x**2)) + 1e-12)


def render_speech(text: str, voice: str, speed: int, snr_db: float | None, seed: int) -> bytes:
    """Padded speech, mixed with white or pink noise at `snr_db` (relative to the speech's power)."""
    rng = np.random.default_rng(seed)
    speech = speak(text, voice, speed)
    speech *= 0.5 / (np.max(np.abs(speech)) + 1e-9)
    pad = np.zeros(int(PAD_S * SAMPLE_RATE))
    x = np.concatenate([pad, speech, pad])
    if snr_db is not None:
        active = speech[np.abs(speech) > 0.02]
        p_speech = float(np.mean(active**2)) if active.size else float(np.mean(speech**2))
        colour = "white" if seed % 2 else "pink"
        x = x + noise(colour, x.size, rng) * np.sqrt(p_speech / 10 ** (snr_db / 10))
    x = x + rng.normal(0.0, DITHER_LSB / 32768.0, x.size)
    return to_pcm(x)


def render_noise(kind: str, level_dbfs: float, seconds: float, seed: int) -> bytes:
    rng = np.random.default_rng(seed)
    n = int(seconds * SAMPLE_RATE)
    x = noise(kind, n, rng) * 10 ** (level_dbfs / 20) + rng.normal(0.0, DITHER_LSB / 32768.0, n)
    return to_pcm(x)


def _cached(key: str) -> Path:
    digest = hashlib.sha1(f"v{SYNTH_VERSION}:{key}".encode()).hexdigest()[:16]
    return cache_dir() / f"{digest}.wav"


def _materialise(path: Path, render: Callable[[], bytes]) -> Path:
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        write_wav(tmp, render())
        tmp.replace(path)
    return path


def speech_clip(text: str, voice: str, speed: int, snr_db: float | None = None) -> Clip:
    """The cached clip of `text` (made on first use)."""
    key = f"speech:{text}:{voice}:{speed}:{snr_db}"
    seed = int(hashlib.sha1(key.encode()).hexdigest()[:8], 16)
    path = _materialise(_cached(key), lambda: render_speech(text, voice, speed, snr_db, seed))
    kind: Kind = "command" if text in COMMAND_WORDS else "oov"
    return Clip(path, kind, text, voice, speed, snr_db)


def noise_clip(kind: str, level_dbfs: float, seconds: float = 1.5, seed: int = 0) -> Clip:
    key = f"noise:{kind}:{level_dbfs}:{seconds}:{seed}"
    path = _materialise(_cached(key), lambda: render_noise(kind, level_dbfs, seconds, seed))
    return Clip(path, "noise", f"{kind}@{level_dbfs:g}dBFS#{seed}")


def speech_set(
    split: Split,
    *,
    snrs: Iterable[float | None] = SNRS_DB,
    words: Iterable[str] | None = None,
    voices: Iterable[str] | None = None,
    speeds: Iterable[int] | None = None,
) -> Iterator[Clip]:
    """Commands and non-commands of one split, in every voice x speed x SNR of that split."""
    if words is None:
        words = COMMAND_WORDS + (OOV_TUNE if split == "tune" else OOV_HELDOUT)
    voices = tuple(voices or (VOICES_TUNE if split == "tune" else VOICES_HELDOUT))
    speeds = tuple(speeds or (SPEEDS_TUNE if split == "tune" else SPEEDS_HELDOUT))
    for word in words:
        for voice in voices:
            for speed in speeds:
                for snr in snrs:
                    yield speech_clip(word, voice, speed, snr)


def noise_set(split: Split, seconds: float = 1.5) -> Iterator[Clip]:
    """Pure noise clips (no speech): every kind at every level, seeds differing by split."""
    base = 0 if split == "tune" else 1000
    for kind in NOISES:
        for level in NOISE_LEVELS_DBFS:
            for seed in range(2):
                yield noise_clip(kind, level, seconds, base + seed)


def recording(parts: list[Clip], gap_s: float = 1.0, noise_dbfs: float = -45.0, seed: int = 7) -> bytes:
    """Clips joined by `gap_s` of silence, all over a continuous pink-noise background at `noise_dbfs`:
    a long stream for the segmenter."""
    rng = np.random.default_rng(seed)
    gap = np.zeros(int(gap_s * SAMPLE_RATE))
    chunks: list[np.ndarray] = []
    for clip in parts:
        chunks.append(gap)
        chunks.append(np.frombuffer(read_wav(clip.path), dtype="<i2").astype(np.float64) / 32768.0)
    chunks.append(gap)
    x = np.concatenate(chunks)
    return to_pcm(x + noise("pink", x.size, rng) * 10 ** (noise_dbfs / 20))
