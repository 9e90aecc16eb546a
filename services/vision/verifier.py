"""A small learned check on each mark the shape and card tests found: is this patch really an X, an O,
a TRIANGLE, or not a mark at all?

Features (`patch_features`): the candidate's grey patch at the pyramid level it was found on, cut
square around its box three times - tight (1.2 x its size: the mark's own strokes), wide (2.2 x: the
card around it, where the neighbouring letters of a word or a sign's other parts show) and context
(4 x: where the card ends, or does not, as for a sign painted on a wall) - each stretched to the
full grey range of the tight patch and resized to 32x32; a HOG descriptor of each
(`hog`: 8x8 cells, 16x16 blocks, 9 orientations: 324 values each), the tight patch's
16x16 pixels, and the shape the geometric tests claimed (one-hot, plus one slot for a loose
candidate in which they found none). 1,232 values.

Model (`Verifier`): a one-hidden-layer perceptron (ReLU) over the standardised features, softmax over
{X, O, TRIANGLE, none}, evaluated with numpy from `verifier.npz` (weights stored as float16). It was
trained by `python -m services.vision.training` (scikit-learn, fixed seed) on candidates harvested
from the tuning generator only (`synthetic.py`); see the vision README. A candidate is kept when the
model gives its claimed shape at least that shape's threshold (`thresholds`) of probability; a loose
candidate is named after its likeliest shape if that reaches the stricter `loose_thresholds`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from schemas.messages import Shape

CLASSES: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
SHAPES: tuple[Shape, ...] = (Shape.X, Shape.O, Shape.TRIANGLE)
MODEL_PATH = Path(__file__).with_name("verifier.npz")
PATCH = 32
TIGHT, WIDE, CONTEXT = 1.2, 2.2, 4.0
CELL, BINS = 8, 9
_CELLS = PATCH // CELL
_CELL_OF = (np.arange(PATCH)[:, None] // CELL * _CELLS + np.arange(PATCH)[None, :] // CELL).ravel()
N_FEATURES = 3 * 324 + 16 * 16 + len(SHAPES) + 1


def hog(*patches: np.ndarray) -> np.ndarray:
    """Histogram of oriented gradients of PATCH x PATCH uint8 patches (Dalal-Triggs layout: 8x8 cells,
    9 unsigned orientations, hard binning, L2-Hys over 2x2-cell blocks with a one-cell stride): 324
    values per patch, concatenated. (OpenCV 5 no longer ships `cv2.HOGDescriptor`; doing several
    patches in one pass saves most of numpy's per-call cost.)"""
    k = len(patches)
    f = np.concatenate(patches, axis=1).astype(np.float32)  # side by side: PATCH x k*PATCH
    gx = np.concatenate(
        [cv2.Sobel(f[:, j * PATCH : (j + 1) * PATCH], cv2.CV_32F, 1, 0, ksize=1) for j in range(k)], axis=1
    )
    gy = cv2.Sobel(f, cv2.CV_32F, 0, 1, ksize=1)  # vertical: no patch borders crossed
    mag, ang = cv2.cartToPolar(gx, gy)
    b = (np.mod(ang, np.pi) * (BINS / np.pi)).astype(np.int64) % BINS
    cell = (
        _CELL_OF.reshape(PATCH, PATCH)[:, None, :] + (np.arange(k) * _CELLS * _CELLS)[None, :, None]
    ).reshape(PATCH, k * PATCH)
    cells = np.bincount((cell * BINS + b).ravel(), weights=mag.ravel(), minlength=k * _CELLS * _CELLS * BINS)
    cells = cells.reshape(k, _CELLS, _CELLS, BINS)
    blocks = np.concatenate(
        [cells[:, :-1, :-1], cells[:, :-1, 1:], cells[:, 1:, :-1], cells[:, 1:, 1:]], axis=3
    ).reshape(-1, 4 * BINS)
    blocks /= np.sqrt((blocks**2).sum(axis=1, keepdims=True) + 1e-6)
    np.minimum(blocks, 0.2, out=blocks)
    blocks /= np.sqrt((blocks**2).sum(axis=1, keepdims=True) + 1e-6)
    return blocks.ravel().astype(np.float32)


def _crop(g: np.ndarray, cx: float, cy: float, side: float) -> np.ndarray:
    side = max(4.0, side)
    patch = cv2.getRectSubPix(g, (round(side), round(side)), (cx, cy))
    return cv2.resize(patch, (PATCH, PATCH), interpolation=cv2.INTER_AREA)


def _stretch(p: np.ndarray, lo: float, hi: float) -> np.ndarray:
    out = (p.astype(np.float32) - lo) * (255.0 / max(hi - lo, 8.0))
    return np.clip(out, 0, 255).astype(np.uint8)


def patch_features(g: np.ndarray, box: tuple[int, int, int, int], shape: Shape | None) -> np.ndarray:
    """The feature vector of a candidate with box `box` (x, y, w, h) in grey image `g`; `shape` is what
    the shape tests claimed, None for a loose candidate (one they found no shape in)."""
    x, y, w, h = box
    cx, cy, size = x + w / 2.0, y + h / 2.0, float(max(w, h))
    tight = _crop(g, cx, cy, TIGHT * size)
    wide = _crop(g, cx, cy, WIDE * size)
    context = _crop(g, cx, cy, CONTEXT * size)
    lo, hi = float(tight.min()), float(tight.max())
    tight, wide, context = _stretch(tight, lo, hi), _stretch(wide, lo, hi), _stretch(context, lo, hi)
    small = cv2.resize(tight, (16, 16), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    onehot = np.array([shape is s for s in SHAPES] + [shape is None], np.float32)
    return np.concatenate([hog(tight, wide, context), small.ravel(), onehot]).astype(np.float32)


@dataclass(frozen=True)
class Verifier:
    mean: np.ndarray
    scale: np.ndarray
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    thresholds: tuple[float, float, float] = (0.25, 0.5, 0.5)
    """the probability X, O and TRIANGLE each need: a false X only stops the robot, a missed X is the
    worst miss, so X needs less; a false O lifts a danger, so O needs a majority"""
    loose_thresholds: tuple[float, float, float] = (0.6, 0.9, 0.85)
    """the same for a loose candidate, whose shape only this model names (no shape test agreed)"""

    @classmethod
    def load(cls, path: Path = MODEL_PATH, thresholds: tuple[float, float, float] | None = None) -> Verifier:
        with np.load(path) as z:
            if z["mean"].shape != (N_FEATURES,) or "loose_threshold" not in z.files:
                raise ValueError(
                    f"{path}: made for {z['mean'].shape[0]} features, this code makes {N_FEATURES}"
                )
            n = int(z["layers"])
            v = cls(
                mean=z["mean"].astype(np.float32),
                scale=z["scale"].astype(np.float32),
                weights=tuple(z[f"w{k}"].astype(np.float32) for k in range(n)),
                biases=tuple(z[f"b{k}"].astype(np.float32) for k in range(n)),
                thresholds=tuple(float(t) for t in np.broadcast_to(z["threshold"], (3,)))  # type: ignore[arg-type]
                if thresholds is None
                else thresholds,
                loose_thresholds=tuple(float(t) for t in np.broadcast_to(z["loose_threshold"], (3,))),  # type: ignore[arg-type]
            )
        if v.mean.shape != (N_FEATURES,) or v.weights[0].shape[0] != N_FEATURES:
            raise ValueError(f"{path}: made for {v.mean.shape[0]} features, this code makes {N_FEATURES}")
        return v

    def save(self, path: Path) -> None:
        arrays: dict[str, np.ndarray] = {
            "layers": np.array(len(self.weights)),
            "mean": self.mean.astype(np.float32),
            "scale": self.scale.astype(np.float32),
            "threshold": np.array(self.thresholds, np.float32),
            "loose_threshold": np.array(self.loose_thresholds, np.float32),
        }
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            arrays[f"w{k}"] = w.astype(np.float16)
            arrays[f"b{k}"] = b.astype(np.float32)
        np.savez_compressed(path, **arrays)  # type: ignore[arg-type]

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        """(n, 4) class probabilities in the order of `CLASSES` for (n, N_FEATURES) features."""
        a = (np.atleast_2d(features) - self.mean) / self.scale
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            a = a @ w + b
            if k < len(self.weights) - 1:
                a = np.maximum(a, 0.0)
        a = a - a.max(axis=1, keepdims=True)
        e = np.exp(a)
        return e / e.sum(axis=1, keepdims=True)

    def accepts(self, g: np.ndarray, box: tuple[int, int, int, int], shape: Shape) -> bool:
        p = self.probabilities(patch_features(g, box, shape))[0]
        return bool(p[CLASSES.index(shape)] >= self.thresholds[SHAPES.index(shape)])

    def name(self, features: np.ndarray) -> tuple[Shape, float, bool]:
        """For a loose candidate's features: the likeliest shape, its probability, and whether that
        reaches the shape's `loose_thresholds`."""
        p = self.probabilities(features)[0]
        k = int(np.argmax(p[: len(SHAPES)]))
        return SHAPES[k], float(p[k]), bool(p[k] >= self.loose_thresholds[k])
