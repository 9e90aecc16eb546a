"""A small learned check on each mark the shape and card tests found: is this patch really an X, an O,
a TRIANGLE, or not a mark at all?

Input (`crops`): the candidate's grey patch at the pyramid level it was found on, cut square around
its box three times - tight (1.2 x its size: the mark's own strokes), wide (2.2 x: the card around it,
where the neighbouring letters of a word or a sign's other parts show) and context (4 x: where the
card ends, or does not, as for a sign painted on a wall) - each stretched to the grey range of the
tight patch and resized to 32x32: three channels of one image. A second input is the shape the
geometric tests claimed (`claim`: one-hot, plus one slot for a loose candidate in which they found
none).

Model (`Verifier`): a small convolutional network (three 3x3 convolution + max-pool stages, then one
hidden layer that also sees the claim), softmax over {X, O, TRIANGLE, none}, in `verifier.onnx` and run
with onnxruntime on one thread, every candidate of a frame in one call (`probabilities`). It was
trained by `python -m services.vision.training` (PyTorch, fixed seed) on candidates harvested from the
tuning generator only (`synthetic.py`); see the vision README. Since round vision23g the committed file
holds two such networks joined by `ensemble.py`: the second, trained with stars, check marks and clock
faces too (`--everyday`), runs on the loose rows only and caps their X probability (a loose candidate is
named X only if both agree); everything else is the first's. Since round vision68b that joined model is the base
of a danger-raised one (`danger_raise.py`): a second joined model, its first network fine-tuned on glossy cards, may
raise a row's X (the higher of the two), never its O. A candidate is kept when the model gives
its claimed shape at least that shape's threshold (`thresholds`) of probability; a loose candidate is
named after its likeliest shape if that reaches the stricter `loose_thresholds`. Both sets of
thresholds are stored in the model file's metadata.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from schemas.messages import Shape

CLASSES: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
SHAPES: tuple[Shape, ...] = (Shape.X, Shape.O, Shape.TRIANGLE)
MODEL_PATH = Path(__file__).with_name("verifier.onnx")
TRIANGLES_PATH = Path(__file__).with_name("verifier_triangles.onnx")
"""a second network, trained with triangles drawn by hand, asked only about triangles (`DetectorConfig.hand_triangle`)"""
PATCH = 32
TIGHT, WIDE, CONTEXT = 1.2, 2.2, 4.0
N_CLAIM = len(SHAPES) + 1  # the claimed shape, one-hot, and one slot for 'loose' (no shape claimed)
INPUT_FORMAT = "crops3x32-claim4"
"""what `crops` and `claim` make; a model for other inputs is refused (its metadata names its format)"""


def _crop(g: np.ndarray, cx: float, cy: float, side: float) -> np.ndarray:
    side = max(4.0, side)
    patch = cv2.getRectSubPix(g, (round(side), round(side)), (cx, cy))
    return cv2.resize(patch, (PATCH, PATCH), interpolation=cv2.INTER_AREA)


def crops(g: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """The network's image input for a candidate with box `box` (x, y, w, h) in grey image `g`: (3,
    PATCH, PATCH) uint8, the tight, wide and context crops, each stretched to the tight crop's grey
    range (at least 8 levels wide)."""
    x, y, w, h = box
    cx, cy, size = x + w / 2.0, y + h / 2.0, float(max(w, h))
    out = np.stack([_crop(g, cx, cy, k * size) for k in (TIGHT, WIDE, CONTEXT)]).astype(np.float32)
    lo, hi = float(out[0].min()), float(out[0].max())
    out -= lo  # in place, in float32: (out - lo) * scale, clipped
    out *= 255.0 / max(hi - lo, 8.0)
    return np.clip(out, 0, 255, out=out).astype(np.uint8)


def claim(shape: Shape | None) -> np.ndarray:
    """The claimed-shape input: one-hot over X, O, TRIANGLE, and 'loose' for None."""
    return np.array([shape is s for s in SHAPES] + [shape is None], np.float32)


def onnx_session(path: Path, what: str) -> Any:
    """An onnxruntime session of the model in `path` on one thread (the vision loop's budget is one
    core); ValueError naming `what` the model should be for a file onnxruntime cannot read."""
    import onnxruntime as ort  # type: ignore[import-untyped,unused-ignore]

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = 1
    opts.inter_op_num_threads = 1
    opts.log_severity_level = 3
    try:
        return ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
    except Exception as e:  # onnxruntime's own exception types: not a readable ONNX model
        raise ValueError(f"{path}: not a {what} model ({e})") from e


def _floats(text: str) -> tuple[float, float, float]:
    values = tuple(float(v) for v in text.split(","))
    if len(values) != len(SHAPES):
        raise ValueError(f"expected {len(SHAPES)} thresholds, got {text!r}")
    return values  # type: ignore[return-value]


@dataclass(frozen=True)
class Verifier:
    session: Any = field(repr=False)
    """an onnxruntime InferenceSession of the network (inputs `crops`, `claim`; output `probabilities`)"""
    thresholds: tuple[float, float, float]
    """the probability X, O and TRIANGLE each need (the committed model's: 0.25, 0.8, 0.8): a false X
    only stops the robot, a missed X is the worst miss, so X needs least; a false O lifts a danger"""
    loose_thresholds: tuple[float, float, float]
    """the same for a loose candidate, whose shape only this model names (no shape test agreed; the
    committed model's: 0.5, 0.95, 0.9)"""

    @classmethod
    def load(cls, path: Path = MODEL_PATH, thresholds: tuple[float, float, float] | None = None) -> Verifier:
        """The model in `path`, on one thread; `thresholds` overrides the stored ones. ValueError for a
        file that is not a model for this code's inputs."""
        session = onnx_session(path, "verifier")
        meta = session.get_modelmeta().custom_metadata_map
        inputs = {i.name: i.shape[1:] for i in session.get_inputs()}
        if meta.get("input_format") != INPUT_FORMAT or inputs != {
            "crops": [3, PATCH, PATCH],
            "claim": [N_CLAIM],
        }:
            raise ValueError(
                f"{path}: made for inputs {meta.get('input_format')!r} {inputs}, this code makes {INPUT_FORMAT}"
            )
        return cls(
            session=session,
            thresholds=_floats(meta["thresholds"]) if thresholds is None else thresholds,
            loose_thresholds=_floats(meta["loose_thresholds"]),
        )

    def probabilities(self, crops: np.ndarray, claims: np.ndarray) -> np.ndarray:
        """(n, 4) class probabilities in the order of `CLASSES` for (n, 3, PATCH, PATCH) uint8 crops and
        (n, 4) claims: one call for the whole batch."""
        if len(crops) == 0:
            return np.zeros((0, len(CLASSES)), np.float32)
        x = np.ascontiguousarray(crops, dtype=np.float32) * np.float32(1.0 / 255.0)
        c = np.ascontiguousarray(claims, dtype=np.float32).reshape(len(crops), N_CLAIM)
        return self.session.run(None, {"crops": x, "claim": c})[0]

    def accepts(self, p: np.ndarray, shape: Shape) -> bool:
        """Whether probabilities `p` (one row) keep a candidate the shape tests took for `shape`."""
        return bool(p[CLASSES.index(shape)] >= self.thresholds[SHAPES.index(shape)])

    def name(self, p: np.ndarray) -> tuple[Shape, float, bool]:
        """For a loose candidate's probabilities `p` (one row): the likeliest shape, its probability,
        and whether that reaches the shape's `loose_thresholds`."""
        k = int(np.argmax(p[: len(SHAPES)]))
        return SHAPES[k], float(p[k]), bool(p[k] >= self.loose_thresholds[k])

    def check(self, g: np.ndarray, box: tuple[int, int, int, int], shape: Shape) -> bool:
        """One candidate on its own (tests, tools): does the model keep `box` in `g` as `shape`?"""
        p = self.probabilities(crops(g, box)[None], claim(shape)[None])[0]
        return self.accepts(p, shape)
