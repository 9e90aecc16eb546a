"""A highlight on a glossy card: the reflection of a lamp that no frame generator draws over a mark.

Cards in a classroom are often laminated, or printed on glossy paper, and a robot's camera looks at them under ceiling
lamps. Where the lamp's reflection falls on the card, the surface reflects light of its own (a specular reflection)
on top of what the ink and the paper scatter: the same light is *added* over ink and paper, so the ink loses its
contrast there, and where the reflection alone reaches the sensor's white, ink and paper are both white and the mark
has a gap. A highlight is drawn here as an elliptical Gaussian lobe of added light, in linear light (gamma 2.2), its
`peak` in units of the sensor's white (1: the lobe's centre alone saturates), clipped.

Used by `bench/vision_bench.py --glare PEAK`: one highlight a frame, centred within the mark's box (anywhere in a
mark-free frame: a glossy thing somewhere in view), and a recall slice by the share of the mark's box washed out.
"""

from __future__ import annotations

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
