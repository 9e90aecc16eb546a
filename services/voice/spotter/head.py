"""The spotter's classifier head: a one-hidden-layer MLP over the utterance's embeddings, in numpy,
with per-command thresholds and the calibration of its published confidence.

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

DEFAULT_HEAD = Path(__file__).with_name("head.npz")
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

    @property
    def classes(self) -> tuple[str, ...]:
        return (*self.vocabulary, "other")

    def hidden(self, feats: np.ndarray) -> np.ndarray:
        """(n, frames, 96) or (frames, 96) embeddings -> the last layer's input."""
        h = (feats.reshape(-1, self.mean.size).astype(np.float32) - self.mean) / self.scale
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
            "meta": np.array(repr(self.meta)),
        }
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
            head = cls(
                vocabulary=tuple(str(v) for v in data["vocabulary"]), mean=data["mean"], scale=data["scale"],
                weights=[data[f"w{i}"].astype(np.float32) for i in range(n)],
                biases=[data[f"b{i}"] for i in range(n)],
                accept=data["accept"].astype(np.float64), sure=data["sure"].astype(np.float64),
                meta={"source": str(path)}, base_last=base,
            )
        except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as exc:  # truncated, not a zip, ...
            raise HeadError(f"{path}: not a spotter head ({exc})") from None
        if n == 0 or head.weights[-1].shape[1] != len(head.classes):
            raise HeadError(f"{path}: output size does not match its vocabulary of {len(head.vocabulary)} words")
        return head
