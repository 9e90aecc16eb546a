"""A fixed, pretrained speech embedding: Google's speech-embedding model as shipped (ONNX) in the
`openwakeword==0.4.0` wheel, run with onnxruntime.

The maths is openWakeWord's (`openwakeword.utils.AudioFeatures`): a mel spectrogram of 16-bit PCM
(`melspectrogram.onnx`, 32 bands, 10 ms hop) transformed as `mel / 10 + 2`, then windows of 76 mel
frames at a step of 8 into `embedding_model.onnx`: one 96-dimensional embedding per 80 ms.

An utterance is placed in the middle of a fixed `WINDOW_S` of audio (padded with quiet noise), so
every utterance gives the same `FRAMES` x 96 embeddings: the classifier's input. The openwakeword
package itself is not imported (it pulls in much more than these two files).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from services.voice.audio import SAMPLE_RATE

MEL_WINDOW = 76
MEL_STEP = 8
EMBED_DIM = 96
FRAMES = 16
"""Embedding frames per utterance window: 16 x 80 ms (each frame sees 0.76 s)."""
WINDOW_S = (MEL_WINDOW + (FRAMES - 1) * MEL_STEP + 4) * 160 / SAMPLE_RATE
"""Audio seconds that give exactly FRAMES embeddings (2.0 s)."""
MAX_SPEECH_S = 1.7
"""A trimmed utterance longer than this is not one command word: it is rejected as "other"."""
PAD_LSB = 3.0


class FeatureError(RuntimeError):
    """The embedding models (openwakeword 0.4.0 wheel) or onnxruntime are missing."""


def model_dir(names: tuple[str, ...] = ("melspectrogram.onnx", "embedding_model.onnx")) -> Path:
    """The openwakeword 0.4.0 wheel's model folder, checked to hold `names` (FeatureError otherwise)."""
    spec = importlib.util.find_spec("openwakeword")
    if spec is None or not spec.submodule_search_locations:
        raise FeatureError("the openwakeword==0.4.0 package (which ships the embedding models) is not installed: "
                           "pip install 'openwakeword==0.4.0'")
    path = Path(next(iter(spec.submodule_search_locations))) / "resources" / "models"
    for name in names:
        if not (path / name).is_file():
            raise FeatureError(f"{path / name} is missing: openwakeword 0.4.0 ships it; newer versions download it")
    return path


@dataclass
class Embedder:
    """PCM -> (frames, 96) speech embeddings, on one CPU thread by default."""

    threads: int = 1

    def __post_init__(self) -> None:
        try:
            import onnxruntime as ort
        except ImportError:
            raise FeatureError("onnxruntime is not installed: pip install onnxruntime") from None
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = self.threads
        opts.inter_op_num_threads = 1
        opts.log_severity_level = 3
        where = model_dir()
        self._mel = ort.InferenceSession(str(where / "melspectrogram.onnx"), opts, providers=["CPUExecutionProvider"])
        self._emb = ort.InferenceSession(str(where / "embedding_model.onnx"), opts, providers=["CPUExecutionProvider"])

    def mel(self, samples: np.ndarray) -> np.ndarray:
        """Samples in int16 units (float32) -> (mel frames, 32)."""
        out = self._mel.run(None, {"input": samples.astype(np.float32)[None, :]})[0]
        return np.squeeze(out) / 10.0 + 2.0

    def embed(self, samples: np.ndarray) -> np.ndarray:
        """Samples in int16 units -> (n, 96) embeddings, one per 80 ms."""
        return self.embed_mel(self.mel(samples))

    def embed_mel(self, spec: np.ndarray) -> np.ndarray:
        """A (transformed) mel spectrogram, as `mel` returns it -> (n, 96) embeddings, one per 80 ms."""
        starts = range(0, spec.shape[0] - MEL_WINDOW + 1, MEL_STEP)
        batch = np.stack([spec[i : i + MEL_WINDOW] for i in starts])[..., None].astype(np.float32)
        return self._emb.run(None, {"input_1": batch})[0].reshape(len(starts), EMBED_DIM)

    def utterance(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        """One utterance (16-bit PCM) centred in a WINDOW_S window -> (FRAMES, 96)."""
        return self.embed(centre(pcm, seed))[:FRAMES]

    def utterance_mel(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        """The mel spectrogram `utterance` embeds: (mel frames, 32) of the centred WINDOW_S window."""
        return self.mel(centre(pcm, seed))


def speech_seconds(pcm: bytes) -> float:
    return len(pcm) / 2 / SAMPLE_RATE


def centre(pcm: bytes, seed: int = 0) -> np.ndarray:
    """The utterance in the middle of WINDOW_S of audio (quiet noise around it; a longer one is cut to
    its middle), as int16-valued float32 samples."""
    x = np.frombuffer(pcm, dtype="<i2").astype(np.float32)
    n = round(WINDOW_S * SAMPLE_RATE)
    if x.size >= n:
        start = (x.size - n) // 2
        return x[start : start + n].copy()
    out = np.random.default_rng(seed).normal(0.0, PAD_LSB, n).astype(np.float32)
    at = (n - x.size) // 2
    out[at : at + x.size] += x
    return out
