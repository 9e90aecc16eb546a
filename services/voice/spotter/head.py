"""The spotter's classifier head: a one-hidden-layer MLP over the utterance's embeddings, in numpy,
with per-command thresholds and the calibration of its published confidence.

A head may look at *crops*: the same MLP applied to several windows of `crop_width` consecutive
embedding frames (starting at `crop_starts`), its hidden activations averaged over the crops. The
last layer is linear, so this is the average of the crops' logits: a small temporal model that does
not care exactly where in the window the word sits (it was trained on every crop as its own sample).

Stored as a small `.npz` (`head.npz` beside this file is the committed default): the vocabulary (class
order; "other" is the extra last class), input standardisation, weights, and for each command two
knots on its raw probability: `accept` (published confidence 0.5: the lowest at which the command is
published) and `sure` (published 0.85). Between the knots the mapping is linear, so for "go" the
reasoner's defaults mean: below `accept` not understood, `accept`..`sure` ask first, above `sure` walk.
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from services.voice.spotter.embedders import SHAPES, SPEECH_EMBEDDING
from services.voice.spotter.features import EMBED_DIM, FRAMES

DEFAULT_HEAD = Path(__file__).with_name("head.npz")
SPEECH_EMBEDDING_HEAD = Path(__file__).with_name("head-speech-embedding.npz")
"""The shipped head on the speech embedding: the walk gate of a head on another embedding, and the head `enroll`
adapts."""
ACCEPT_CONFIDENCE = 0.5
SURE_CONFIDENCE = 0.85


class HeadError(ValueError):
    """A head file that cannot be used."""


@dataclass
class Head:
    vocabulary: tuple[str, ...]
    mean: np.ndarray
    scale: np.ndarray
    weights: list[np.ndarray]
    biases: list[np.ndarray]
    accept: np.ndarray
    """Per command (vocabulary order): raw probability published as confidence 0.5."""
    sure: np.ndarray
    """Per command: raw probability published as confidence 0.85."""
    meta: dict[str, Any] = field(default_factory=dict)
    base_last: tuple[np.ndarray, np.ndarray] | None = None
    """An enrolled head keeps the calibrated head's last layer: enrolment may make the robot *ask*
    about a "go" more readily, but it walks without asking only if the calibrated head is sure too."""
    crop_width: int = 0
    """Embedding frames per crop; 0: the whole window is one input."""
    crop_starts: tuple[int, ...] = ()
    embedding: str = SPEECH_EMBEDDING
    """The speech embedding the head reads (`embedders.EMBEDDINGS`); heads that record none read this one."""

    @property
    def classes(self) -> tuple[str, ...]:
        return (*self.vocabulary, "other")

    def hidden(self, feats: np.ndarray) -> np.ndarray:
        """(n, frames, 96) or (frames, 96) embeddings -> the last layer's input (averaged over crops)."""
        if not self.crop_width:
            return self._hidden(feats.reshape(-1, self.mean.size))
        x = feats.reshape(-1, FRAMES, EMBED_DIM)  # (n, frames, 96), (frames, 96) or flattened (n, frames * 96)
        return np.mean([self._hidden(x[:, s : s + self.crop_width].reshape(len(x), -1)) for s in self.crop_starts],
                       axis=0)

    def _hidden(self, flat: np.ndarray) -> np.ndarray:
        h = (flat.astype(np.float32) - self.mean) / self.scale
        for w, b in zip(self.weights[:-1], self.biases[:-1], strict=True):
            h = np.maximum(h @ w + b, 0.0)
        return h

    def probabilities(self, feats: np.ndarray, *, base: bool = False) -> np.ndarray:
        """(n, frames, 96) or (frames, 96) embeddings -> (n, classes) softmax probabilities
        (`base`: of the calibrated head an enrolled head was made from)."""
        w, b = self.base_last if base and self.base_last is not None else (self.weights[-1], self.biases[-1])
        z = self.hidden(feats) @ w + b
        z -= z.max(axis=1, keepdims=True)
        e = np.exp(z)
        return e / e.sum(axis=1, keepdims=True)

    def confidence(self, index: int, p: float) -> float:
        """Calibrated, published confidence of command `index` at raw probability `p`."""
        a, s = float(self.accept[index]), float(self.sure[index])
        xs = [0.0, a, max(s, a + 1e-6), 1.0 + 1e-6]
        return float(np.interp(p, xs, [0.0, ACCEPT_CONFIDENCE, SURE_CONFIDENCE, 1.0]))

    def save(self, path: Path) -> None:
        arrays: dict[str, np.ndarray] = {
            "vocabulary": np.array(self.vocabulary), "mean": self.mean.astype(np.float32),
            "scale": self.scale.astype(np.float32), "accept": self.accept, "sure": self.sure,
            "meta": np.array(repr(self.meta)), "embedding": np.array(self.embedding),
        }
        if self.crop_width:
            arrays["crop"] = np.array([self.crop_width, *self.crop_starts], dtype=np.int32)
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            arrays[f"w{i}"] = w.astype(np.float16)
            arrays[f"b{i}"] = b.astype(np.float32)
        if self.base_last is not None:
            arrays["base_w"], arrays["base_b"] = self.base_last[0].astype(np.float16), self.base_last[1]
        np.savez_compressed(path, **arrays)  # type: ignore[arg-type]

    @classmethod
    def load(cls, path: Path | str = DEFAULT_HEAD) -> Head:
        path = Path(path)
        try:
            data = np.load(path, allow_pickle=False)
            n = sum(1 for k in data.files if k.startswith("w"))
            base = (data["base_w"].astype(np.float32), data["base_b"]) if "base_w" in data.files else None
            crop = [int(v) for v in data["crop"]] if "crop" in data.files else [0]
            head = cls(
                vocabulary=tuple(str(v) for v in data["vocabulary"]), mean=data["mean"], scale=data["scale"],
                weights=[data[f"w{i}"].astype(np.float32) for i in range(n)],
                biases=[data[f"b{i}"] for i in range(n)],
                accept=data["accept"].astype(np.float64), sure=data["sure"].astype(np.float64),
                meta={"source": str(path)}, base_last=base, crop_width=crop[0], crop_starts=tuple(crop[1:]),
                embedding=str(data["embedding"]) if "embedding" in data.files else SPEECH_EMBEDDING,
            )
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as exc:  # truncated, not a zip, ...
            raise HeadError(f"{path}: not a spotter head ({exc})") from None
        if n == 0 or head.weights[-1].shape[1] != len(head.classes):
            raise HeadError(f"{path}: output size does not match its vocabulary of {len(head.vocabulary)} words")
        if head.embedding not in SHAPES:
            raise HeadError(f"{path}: trained on an unknown speech embedding {head.embedding!r}")
        frames, dim = SHAPES[head.embedding]
        if not head.crop_width and head.mean.size != frames * dim:
            raise HeadError(f"{path}: input size {head.mean.size} is not {frames} x {dim}, what {head.embedding} gives")
        if head.crop_width and (head.embedding != SPEECH_EMBEDDING or not head.crop_starts or min(head.crop_starts) < 0
                                or max(head.crop_starts) + head.crop_width > FRAMES
                                or head.mean.size != head.crop_width * EMBED_DIM):
            raise HeadError(f"{path}: crops {crop} do not fit {FRAMES} frames of {EMBED_DIM} or the input size")
        return head
