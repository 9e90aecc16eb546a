"""A learned look at the whole frame: where might a mark be, whatever its components look like?

The contour detector only judges connected components of a binarised frame. A small mark smeared by
motion blur into its card's edge, a triangle broken by a finger, a pale mark under a gradient: often no
component matches the mark at all, and nothing downstream can find it again (`bench/vision_stages.py`,
"no component"). The proposer is a small fully convolutional network (CenterNet's scheme: one heatmap
of mark centres per shape, and each centre's box size and sub-cell offset) run on the frame's grey
image at half the detector's scale (320x240 for 640x480), in `proposer.onnx` with onnxruntime on
one thread. Its weights and activations are int8 (static quantisation, calibrated on tuning frames):
about two thirds of the float model's time, at the same proposals on the training's held-back frames.

Its peaks are proposals, not marks: the detector (`DetectorConfig.propose`, on since round vision19) keeps a
proposal only where it found nothing itself and only when the learned verifier (`verifier.py`), shown the
proposal's box as a loose candidate, gives the proposed shape at least `DetectorConfig.propose_thresholds`.
It was trained by `python -m
services.vision.proposer_training` on the tuning generator only (`synthetic.py`); see the vision README.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision.verifier import onnx_session

MODEL_PATH = Path(__file__).with_name("proposer.onnx")
SHAPES: tuple[Shape, ...] = (Shape.X, Shape.O, Shape.TRIANGLE)
SCALE = 2
"""the network sees the frame at 1/SCALE of the detector's working size: a 26 px mark is 13 px there (at a
quarter it was 6 px, and the first model's recall of marks under 80 px was 0.77 against 1.0 above)"""
STRIDE = 8
"""one output cell per STRIDE x STRIDE input pixels (16 x 16 px of a 640x480 frame)"""
INPUT_FORMAT = "grey-half-centernet-v1"
"""what `Proposer.propose` feeds and reads; a model for other inputs is refused"""
HEADS = len(SHAPES) + 4
"""output channels: a centre heatmap per shape (sigmoid), log width and height in input pixels, and the
centre's offset within its cell (x, y, in cells)"""


@dataclass(frozen=True)
class Proposal:
    shape: Shape
    score: float
    box: tuple[int, int, int, int]
    """x, y, w, h in the detector's working pixels"""


def network_input(gray: np.ndarray) -> np.ndarray:
    """The grey frame shrunk to 1/SCALE (INTER_AREA), as (1, 1, h, w) float32 in 0..1. The training
    script makes its inputs with this very function."""
    h, w = gray.shape[:2]
    small = cv2.resize(gray, (max(STRIDE, w // SCALE), max(STRIDE, h // SCALE)), interpolation=cv2.INTER_AREA)
    return (small.astype(np.float32) * np.float32(1.0 / 255.0))[None, None]


def decode(out: np.ndarray, threshold: float, limit: int = 8) -> list[Proposal]:
    """Peaks of the (HEADS, h, w) output that reach `threshold` (local maxima over 3x3 cells across the
    three shapes, best first, at most `limit`), as boxes in the detector's working pixels."""
    heat = out[: len(SHAPES)]
    best = heat.max(axis=0)
    peaks = (best >= threshold) & (best >= cv2.dilate(best, np.ones((3, 3), np.uint8)))
    ys, xs = np.nonzero(peaks)
    order = np.argsort(-best[ys, xs])[:limit]
    cell = STRIDE * SCALE
    found: list[Proposal] = []
    for y, x in zip(ys[order], xs[order], strict=True):
        k = int(np.argmax(heat[:, y, x]))
        w = float(np.exp(out[len(SHAPES), y, x])) * SCALE
        h = float(np.exp(out[len(SHAPES) + 1, y, x])) * SCALE
        cx = (x + float(out[len(SHAPES) + 2, y, x])) * cell
        cy = (y + float(out[len(SHAPES) + 3, y, x])) * cell
        box = (round(cx - w / 2), round(cy - h / 2), max(1, round(w)), max(1, round(h)))
        found.append(Proposal(SHAPES[k], float(heat[k, y, x]), box))
    return found


@dataclass(frozen=True)
class Proposer:
    session: Any = field(repr=False)
    """an onnxruntime InferenceSession (input `frame`, output `heads`)"""

    @classmethod
    def load(cls, path: Path = MODEL_PATH) -> Proposer:
        """The model in `path`, on one thread; ValueError for a file that is not a proposer model."""
        session = onnx_session(path, "proposer")
        meta = session.get_modelmeta().custom_metadata_map
        if meta.get("input_format") != INPUT_FORMAT:
            raise ValueError(
                f"{path}: made for inputs {meta.get('input_format')!r}, this code makes {INPUT_FORMAT}"
            )
        return cls(session=session)

    def heads(self, gray: np.ndarray) -> np.ndarray:
        """The network's (HEADS, h, w) output for a grey frame at the detector's working size."""
        out: np.ndarray = self.session.run(None, {"frame": network_input(gray)})[0][0]
        return out

    def propose(self, gray: np.ndarray, threshold: float) -> list[Proposal]:
        """Peaks of at least `threshold` (`decode`) in a grey frame at the detector's working size."""
        return decode(self.heads(gray), threshold)
