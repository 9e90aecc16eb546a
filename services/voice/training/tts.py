"""Offline text-to-speech engines used to make training and evaluation speech.

Each voice is `engine:name`: `espeak:<language>+<variant>` (espeak-ng), `flite:<voice>` (flite's
built-in voices: kal16 is a diphone voice, awb/rms/slt are clustergen voices built from recordings
of three different speakers) and Festival's `festival:kal` and `festival:ked` (diphone voices: ked is
a third recorded American male speaker) and `festival:slt_hts` (the slt speaker through Festival's HTS
statistical-parametric synthesiser: another engine than flite's clustergen slt; it ignores the speed).
Every engine returns float samples at 16 kHz; speed is a duration factor (1.0 = the engine's default,
1.2 = 20 % slower) and pitch a factor on the engine's base pitch.

A voice may end in `@vtl<factor>` (`flite:awb@vtl1.15`): a *virtual speaker* whose vocal tract is
shorter (factor > 1: formants scaled up, towards a child's or a woman's) or longer (< 1) than the
engine's speaker (`vocal_tract`). Pitch and duration are kept: the engine speaks at pitch / factor and
duration x factor, then the audio is resampled by the factor, which scales every frequency (formants
and pitch) by it and the duration by its inverse. This is how two recorded training speakers become
many (vocal-tract-length perturbation; held-out speakers differ from the training ones mostly there).
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


FESTIVAL_VOICES = {"kal": "kal_diphone", "ked": "ked_diphone", "slt_hts": "cmu_us_slt_arctic_hts"}
"""`festival:<name>` -> Festival's voice function `voice_<value>`."""
FESTIVAL_PACKAGES = {"kal": "festvox-kallpc16k", "ked": "festvox-kdlpc16k", "slt_hts": "festvox-us-slt-hts"}
"""The Debian package that carries each Festival voice."""


def festival(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    if voice not in FESTIVAL_VOICES:
        raise TtsError(f"unknown Festival voice {voice!r}: one of {', '.join(FESTIVAL_VOICES)}")
    argv = ["text2wave", "-o", "", "-eval", f"(voice_{FESTIVAL_VOICES[voice]})",
            "-eval", f"(Parameter.set 'Duration_Stretch {speed:.3f})"]
    if round(pitch, 3) != 1.0 and FESTIVAL_VOICES[voice].endswith("_diphone"):
        # the diphone voices' intonation model (Int_Targets_LR) maps onto this mean and spread
        lr = f"(target_f0_mean {105 * pitch:.1f}) (target_f0_std {15 * pitch:.1f}) (model_f0_mean 170) (model_f0_std 34)"
        argv += ["-eval", f"(set! int_lr_params '({lr}))"]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.wav"
        argv[2] = str(out)
        try:
            _run(argv, stdin=text.encode())
        except TtsError as exc:
            raise TtsError(f"{exc} (is Festival's {voice} voice installed? apt-get install "
                           f"{FESTIVAL_PACKAGES[voice]})") from None
        return _wav_samples(out.read_bytes())


ENGINES = {"espeak": espeak, "flite": flite, "festival": festival}


VTL_MARK = "@vtl"


def vocal_tract(x: np.ndarray, factor: float) -> np.ndarray:
    """Every frequency of `x` scaled by `factor` (and its duration by 1 / factor): resampling."""
    up = 200
    return resample_poly(x, up, round(up * factor))


def virtual_speaker(voice: str, factor: float) -> str:
    return voice if round(factor, 2) == 1.0 else f"{voice}{VTL_MARK}{factor:.2f}"


def synthesise(text: str, voice: str, speed: float = 1.0, pitch: float = 1.0) -> np.ndarray:
    """`voice` is `engine:name[@vtl<factor>]`; returns float samples at 16 kHz, peak-normalised to 0.5."""
    base, _, warp = voice.partition(VTL_MARK)
    engine, _, name = base.partition(":")
    if engine not in ENGINES:
        raise TtsError(f"unknown TTS engine {engine!r} in {voice!r}: one of {', '.join(ENGINES)}")
    try:
        factor = float(warp) if warp else 1.0
    except ValueError:
        raise TtsError(f"bad vocal-tract factor in {voice!r}") from None
    if not 0.5 <= factor <= 2.0:
        raise TtsError(f"vocal-tract factor {factor} in {voice!r} is outside 0.5-2.0")
    x = ENGINES[engine](text, name, speed * factor, pitch / factor)
    if factor != 1.0:
        x = vocal_tract(x, factor)
    if x.size == 0 or not np.any(x):
        raise TtsError(f"{voice} produced no audio for {text!r}")
    return 0.5 * x / np.max(np.abs(x))
