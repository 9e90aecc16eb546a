"""A highlight on a glossy card: the reflection of a lamp that no frame generator draws over a mark.

Cards in a classroom are often laminated, or printed on glossy paper, and a robot's camera looks at them under ceiling
lamps. Where the lamp's reflection falls on the card, the surface reflects light of its own (a specular reflection)
on top of what the ink and the paper scatter: the same light is *added* over ink and paper, so the ink loses its
contrast there, and where the reflection alone reaches the sensor's white, ink and paper are both white and the mark
has a gap. A highlight is drawn here as an elliptical Gaussian lobe of added light, in linear light (gamma 2.2), its
`peak` in units of the sensor's white (1: the lobe's centre alone saturates), clipped.

Used by `bench/vision_bench.py --glare PEAK`: one highlight a frame, centred within the mark's box (anywhere in a
mark-free frame: a glossy thing somewhere in view), and a recall slice by the share of the mark's box washed out; and by
`bench/vision_clips.py --glare PEAK`: one highlight a clip, on the card (`glare_clip`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

WASHED = 0.9
"""Added light (linear, sensor white 1) at which a pixel counts as washed out: the darkest ink there reaches 0.95 of
white in the image, as light as paper."""


@dataclass(frozen=True)
class Highlight:
    """A lamp's reflection: centre (x, y) in pixels, semi-axes (a, b) in pixels where the lobe has fallen to e^-2 of
    its `peak`, the major axis's angle in radians."""

    centre: tuple[float, float]
    axes: tuple[float, float]
    angle: float
    peak: float

    def light(self, height: int, width: int) -> np.ndarray:
        """The light it adds to each pixel of a `height` x `width` frame (linear, sensor white 1), float32."""
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        dx, dy = xs - self.centre[0], ys - self.centre[1]
        c, s = math.cos(self.angle), math.sin(self.angle)
        u, v = (c * dx + s * dy) / self.axes[0], (-s * dx + c * dy) / self.axes[1]
        return (self.peak * np.exp(-2.0 * (u * u + v * v))).astype(np.float32)


def draw_highlight(
    rng: np.random.Generator, peak: float, height: int, width: int, box: tuple[int, int, int, int] | None = None
) -> Highlight:
    """A highlight over the mark's `box` (x, y, w, h): its centre anywhere within the box, its major semi-axis 0.15 to
    0.6 of the box's larger side (at least 4 px), its minor one 0.3 to 1 of that; without a box anywhere in the frame,
    20 to 100 px. Its peak is `peak` x U(0.5, 1)."""
    if peak < 0:
        raise ValueError(f"a highlight's peak is a share of the sensor's white, 0 or more, got {peak}")
    if box is not None:
        x, y, w, h = box
        centre = (x + rng.uniform(0, w), y + rng.uniform(0, h))
        major = max(4.0, rng.uniform(0.15, 0.6) * max(w, h))
    else:
        centre = (rng.uniform(0, width), rng.uniform(0, height))
        major = rng.uniform(20.0, 100.0)
    minor = major * rng.uniform(0.3, 1.0)
    return Highlight(centre, (major, minor), rng.uniform(0, math.pi), peak * rng.uniform(0.5, 1.0))


def glared(img: np.ndarray, light: np.ndarray) -> np.ndarray:
    """`img` (uint8, grey or colour) with `light` (per pixel, linear) added in linear light (gamma 2.2), clipped."""
    linear = (img.astype(np.float32) / 255.0) ** 2.2
    linear += light.reshape(light.shape + (1,) * (img.ndim - 2))
    return np.round(np.clip(linear, 0.0, 1.0) ** (1 / 2.2) * 255.0).astype(np.uint8)


def washed_share(light: np.ndarray, box: tuple[int, int, int, int]) -> float:
    """The share of `box`'s pixels (within the frame) where the added light reaches `WASHED`: ink there is white."""
    x, y, w, h = box
    part = light[max(0, y) : y + h, max(0, x) : x + w]
    return float(np.count_nonzero(part >= WASHED)) / part.size if part.size else 0.0


def glare_spot(
    img: np.ndarray, rng: np.random.Generator, peak: float, box: tuple[int, int, int, int] | None = None
) -> tuple[np.ndarray, float]:
    """`img` with a highlight drawn for it (`draw_highlight`), and the share of `box` it washes out (0 without one)."""
    h, w = img.shape[:2]
    light = draw_highlight(rng, peak, h, w, box).light(h, w)
    return glared(img, light), washed_share(light, box) if box is not None else 0.0


def glare_clip(
    frames: list[np.ndarray],
    boxes: list[tuple[int, int, int, int] | None],
    rng: np.random.Generator,
    peak: float,
    fps: float,
) -> list[np.ndarray]:
    """A clip's `frames` with one highlight on its glossy card. It is drawn (`draw_highlight`) over the mark's box in
    the first frame that shows it, then stays at its place on the card (it follows the box, and grows and shrinks with
    it) while sliding across the card at up to one mark's size a second each way, as a card held by a hand turns under
    the lamp. Frames without the mark's box (before the card is up, a mark-free clip) are left as they are: the card
    is then mostly out of view."""
    shown = next(((i, b) for i, b in enumerate(boxes) if b is not None), None)
    if shown is None:
        return frames
    first, (x0, y0, w0, h0) = shown
    h, w = frames[0].shape[:2]
    size0 = max(w0, h0, 1)
    spot = draw_highlight(rng, peak, h, w, (x0, y0, w0, h0))
    at = ((spot.centre[0] - x0) / size0, (spot.centre[1] - y0) / size0)  # its place, in mark sizes from the box
    drift = rng.uniform(-1.0, 1.0, 2)  # mark sizes a second
    out = []
    for k, (frame, box) in enumerate(zip(frames, boxes, strict=True)):
        if box is None:
            out.append(frame)
            continue
        size, t = max(box[2], box[3], 1), (k - first) / fps
        moved = dataclasses.replace(
            spot,
            centre=(box[0] + (at[0] + drift[0] * t) * size, box[1] + (at[1] + drift[1] * t) * size),
            axes=(spot.axes[0] * size / size0, spot.axes[1] * size / size0),
        )
        out.append(glared(frame, moved.light(h, w)))
    return out
