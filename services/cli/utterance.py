"""Speak to the robot: synthesise words with espeak-ng into the voice service's spool folder.

The voice service (source `watch:<dir>`) decodes each complete WAV that appears in that folder
with its real recogniser, exactly as it would a recording.
"""

from __future__ import annotations

import io
import shutil
import subprocess
import uuid
import wave
from pathlib import Path

import numpy as np

RATE = 16_000
DEFAULT_VOICE = "en-us+f1"
"""espeak-ng voice of the demo: the one on which the voice service recognises stand, down, yes, no
and stop at 120 and 150 words a minute (on plain en-us it hears "down" as "no")."""


class SpeechSynthesisError(RuntimeError):
    pass


def synthesise(text: str, *, voice: str = DEFAULT_VOICE, speed: int = 150) -> np.ndarray:
    """16 kHz mono int16 samples of `text` spoken by espeak-ng."""
    exe = shutil.which("espeak-ng")
    if exe is None:
        raise SpeechSynthesisError("espeak-ng is not installed: sudo apt-get install espeak-ng")
    out = subprocess.run([exe, "-v", voice, "-s", str(speed), "--stdout", text], capture_output=True,
                         timeout=30, check=False)
    if out.returncode != 0:
        raise SpeechSynthesisError(f"espeak-ng failed: {out.stderr.decode(errors='replace').strip()}")
    with wave.open(io.BytesIO(out.stdout)) as w:
        rate = w.getframerate()
        samples = np.frombuffer(w.readframes(w.getnframes()), dtype=np.int16).astype(np.float64)
    return _resample(samples, rate, RATE)


def _resample(x: np.ndarray, src: int, dst: int) -> np.ndarray:
    """Band-limited resampling by FFT (clips are short, so one transform is cheap)."""
    if src == dst:
        return x.astype(np.int16)
    n = int(round(len(x) * dst / src))
    spectrum = np.fft.rfft(x)
    keep = n // 2 + 1
    y = np.fft.irfft(spectrum[:keep] if keep <= len(spectrum) else
                     np.pad(spectrum, (0, keep - len(spectrum))), n) * (n / len(x))
    return np.clip(y, -32768, 32767).astype(np.int16)


def write_wav(path: Path, samples: np.ndarray, *, pad_s: float = 0.3, seed: int = 0) -> None:
    """Write a 16 kHz mono WAV with a little dithered silence around the words."""
    rng = np.random.default_rng(seed)
    pad = (rng.normal(0, 3, int(pad_s * RATE))).astype(np.int16)
    audio = np.concatenate([pad, samples, pad])
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(audio.tobytes())


def speak_into(spool: Path, text: str, *, voice: str = DEFAULT_VOICE, speed: int = 150) -> Path:
    """Drop one utterance into `spool`, atomically (written under a .tmp name, then renamed)."""
    spool.mkdir(parents=True, exist_ok=True)
    name = f"{uuid.uuid4().hex[:12]}.wav"
    tmp = spool / f"{name}.tmp"
    write_wav(tmp, synthesise(text, voice=voice, speed=speed))
    final = spool / name
    tmp.replace(final)
    return final
