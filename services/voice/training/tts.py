"""Offline text-to-speech engines used to make training and evaluation speech.

Each voice is `engine:name`: `espeak:<language>+<variant>` (espeak-ng), `flite:<voice>` (flite's
built-in voices: kal16 is a diphone voice, awb/rms/slt are clustergen voices built from recordings
of three different speakers) and `festival:kal` (Festival's diphone voice). Every engine returns float
samples at 16 kHz; speed is a duration factor (1.0 = the engine's default, 1.2 = 20 % slower) and
pitch a factor on the engine's base pitch.
"""

from __future__ import annotations

import io
import shutil
import subprocess
import tempfile
import wave
from math import gcd
from pathlib import Path

import numpy as np
from scipy.signal import resample_poly

from services.voice.audio import SAMPLE_RATE


class TtsError(RuntimeError):
    """A TTS engine that is missing or failed."""


def _wav_samples(data: bytes) -> np.ndarray:
    with wave.open(io.BytesIO(data), "rb") as w:
        rate = w.getframerate()
        x = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(np.float64) / 32768.0
    if rate != SAMPLE_RATE:
        g = gcd(SAMPLE_RATE, rate)
        x = resample_poly(x, SAMPLE_RATE // g, rate // g)
    return x


def _run(argv: list[str], stdin: bytes | None = None) -> bytes:
    if shutil.which(argv[0]) is None:
        raise TtsError(f"{argv[0]} is not installed (apt-get install espeak-ng flite festival)")
    try:
        return subprocess.run(argv, input=stdin, capture_output=True, check=True, timeout=30).stdout
    except subprocess.CalledProcessError as exc:
        raise TtsError(f"{argv[0]} failed: {exc.stderr.decode(errors='replace')[:200]}") from None


def espeak(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    wpm = round(165 / speed)
    return _wav_samples(_run(["espeak-ng", "-v", voice, "-s", str(wpm), "-p", str(round(50 * pitch)),
                              "--stdout", text]))


def flite(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.wav"
        argv = ["flite", "-voice", voice, "-t", text, "-o", str(out), "--setf", f"duration_stretch={speed:.3f}"]
        base = 100.0 if voice in ("kal", "kal16", "awb", "rms") else 170.0
        argv += ["--setf", f"int_f0_target_mean={base * pitch:.1f}"]
        _run(argv)
        return _wav_samples(out.read_bytes())


def festival(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.wav"
        _run(["text2wave", "-o", str(out), "-eval", f"(voice_{voice}_diphone)",
              "-eval", f"(Parameter.set 'Duration_Stretch {speed:.3f})"], stdin=text.encode())
        return _wav_samples(out.read_bytes())


ENGINES = {"espeak": espeak, "flite": flite, "festival": festival}


def synthesise(text: str, voice: str, speed: float = 1.0, pitch: float = 1.0) -> np.ndarray:
    """`voice` is `engine:name`; returns float samples at 16 kHz, peak-normalised to 0.5."""
    engine, _, name = voice.partition(":")
    if engine not in ENGINES:
        raise TtsError(f"unknown TTS engine {engine!r} in {voice!r}: one of {', '.join(ENGINES)}")
    x = ENGINES[engine](text, name, speed, pitch)
    if x.size == 0 or not np.any(x):
        raise TtsError(f"{voice} produced no audio for {text!r}")
    return 0.5 * x / np.max(np.abs(x))
