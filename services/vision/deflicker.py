"""The bands of a flickering light, taken out of a frame before detection (`DetectorConfig.deflicker`).

Fluorescent tubes and many LED lamps flicker at twice the mains frequency (100 or 120 Hz), or at their dimmer's PWM
frequency, and a rolling shutter exposes each row of a frame a little later than the one above it: each row gets its
own share of the light, and the frame is crossed by bright and dark bands (`bench/flicker.py`, `bench/vision_bench.py --flicker`). The
detector's tests compare grey levels (a loose candidate's surround at least 35 levels lighter than its ink, the card's
paper at least 25 over the ink), so in a dark band a mark's contrast falls under them.

A band multiplies a row's light, and through a camera's tone curve (about a power law) the row's grey levels too; the
scene's own edges are local. So the bands' log gain, row to row, is the median over the row's pixels of the log grey
level's step to the next row (at half resolution, every other column, pixels neither near black nor clipped), and
their gain is its running sum. That profile, less a quadratic trend (which it cannot tell from the scene's own
shading), is fitted by a Fourier series of `harmonics` terms (ridge-regularised) for each period of a grid
(`PERIODS`: 16 rows, a fast PWM dimmer, to 480, one cycle a frame); the best period's fit is taken for bands if it
explains at least `min_share` of the profile's variance and its gain varies by at least `min_depth` peak to peak, and
each row is then multiplied by the inverse of its gain (at most `max_gain` either way). A frame without bands but
with the light changing smoothly from top to bottom can pass the test too; then it is that change that is evened
out.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

PERIODS: tuple[float, ...] = tuple(float(p) for p in np.geomspace(16, 480, 320))
"""The band periods tried, in rows of a 480-row frame (scaled with the frame's height), 1.1 % apart: over the frame's
height the nearest drifts from the bands by at most a sixth of a cycle for the shortest (30 cycles), less for longer."""
RIDGE = 0.1
"""The Fourier coefficients' ridge penalty: keeps a fit at a period the profile barely shows from swinging wildly."""
LOG_GREY = np.log(np.arange(256, dtype=np.float32) + 1.0)
MIN_SHARE = 0.9
"""The share of the rows' gain profile the bands must explain (round vision62 chose it on tuning seed 7222)."""
MIN_DEPTH = 1.15
"""The bands' least peak-to-peak gain."""


@dataclass(frozen=True)
class Bands:
    """The bands found in a frame: their period (rows), the share of the detrended gain profile they explain, their
    gain's peak-to-peak ratio, and each row's gain (the frame's mean is 1)."""

    period: float
    share: float
    depth: float
    gain: np.ndarray


def _design(rows: int, periods: np.ndarray, harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """For each period: the design [quadratic trend | Fourier terms] (P, rows, 3 + 2h) and its ridge solution's
    matrix (P, 3 + 2h, rows)."""
    y = np.arange(rows, dtype=np.float64)
    u = y / rows - 0.5
    trend = np.broadcast_to(np.stack([np.ones(rows), u, u * u], axis=1), (periods.size, rows, 3))
    phase = 2 * np.pi * y[None, :, None] * np.arange(1, harmonics + 1)[None, None, :] / periods[:, None, None]
    x = np.concatenate([trend, np.sin(phase), np.cos(phase)], axis=2)
    ridge = np.diag([0.0] * 3 + [RIDGE] * (2 * harmonics))
    xt = x.transpose(0, 2, 1)
    return x, np.linalg.solve(xt @ x + ridge, xt)


@lru_cache(maxsize=8)
def _grid(rows: int, harmonics: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The grid's periods (rows) with their designs and ridge solutions (`_design`), and the quadratic trend's
    least-squares projection (rows, rows), for `rows` rows."""
    periods = np.array(PERIODS) * rows / 480.0
    x, solve = _design(rows, periods, harmonics)
    trend = x[0, :, :3]
    return periods, x, solve, trend @ np.linalg.pinv(trend)


def _fit(profile: np.ndarray, x: np.ndarray, solve: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each design's coefficients for `profile` and its residual sum of squares."""
    coef = solve @ profile
    fitted = np.matmul(x, coef[:, :, None])[:, :, 0]
    return coef, ((profile[None, :] - fitted) ** 2).sum(axis=1)


def gain_profile(gray: np.ndarray) -> np.ndarray:
    """The log of each row's gain at half resolution, up to a constant: the running sum of the median step of the log
    grey level from each row to the next."""
    half = cv2.resize(gray, (max(1, gray.shape[1] // 2), max(1, gray.shape[0] // 2)), interpolation=cv2.INTER_AREA)
    half = half[:, ::2]
    logs = LOG_GREY[half]
    usable = (half > 12) & (half < 250)
    steps = np.where(usable[1:] & usable[:-1], logs[1:] - logs[:-1], np.nan)
    with warnings.catch_warnings():  # a row with no usable pixel (black, or clipped): no step there
        warnings.simplefilter("ignore", RuntimeWarning)
        median = np.nan_to_num(np.nanmedian(steps, axis=1))
    return np.concatenate([[0.0], np.cumsum(median, dtype=np.float64)])


def find_bands(gray: np.ndarray, harmonics: int = 3) -> Bands:
    """The strongest periodic row gain of a grey frame (bands or not: see `Bands.share` and `Bands.depth`)."""
    profile = gain_profile(gray)
    rows = profile.size
    periods, x, solve, trend = _grid(rows, harmonics)
    profile = profile - trend @ profile
    total = float(profile @ profile)
    if total <= 1e-12:
        return Bands(0.0, 0.0, 1.0, np.ones(gray.shape[0]))
    coef, residual = _fit(profile, x, solve)
    # a period's multiples fit as well through their harmonics: the best fit near the shortest period that fits
    # within 2 % of the best
    shortest = periods[np.flatnonzero(residual <= residual.min() + 0.02 * (total - residual.min()))[0]]
    near = np.flatnonzero(np.abs(np.log(periods / shortest)) <= 0.06)
    best = int(near[np.argmin(residual[near])])
    periodic = x[best, :, 3:] @ coef[best, 3:]
    full = np.interp((np.arange(gray.shape[0]) + 0.5) / 2.0 - 0.5, np.arange(rows), periodic)
    gain = np.exp(full - full.mean())
    share = max(0.0, 1.0 - float(residual[best]) / total)
    return Bands(float(periods[best] * gray.shape[0] / rows), share, float(gain.max() / gain.min()), gain)


def deflicker(gray: np.ndarray, min_share: float = MIN_SHARE, min_depth: float = MIN_DEPTH, max_gain: float = 4.0,
              harmonics: int = 3) -> np.ndarray:
    """`gray` with its rows' flicker gain divided out, or `gray` itself where no bands pass the tests."""
    if gray.shape[0] < 64:
        return gray
    bands = find_bands(gray, harmonics)
    if bands.share < min_share or bands.depth < min_depth:
        return gray
    scale = np.clip(1.0 / bands.gain, 1.0 / max_gain, max_gain).astype(np.float32)
    return np.clip(gray.astype(np.float32) * scale[:, None] + 0.5, 0, 255).astype(np.uint8)
