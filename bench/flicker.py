"""A flickering lamp as a rolling-shutter camera sees it: the bright and dark bands no frame generator draws.

Fluorescent tubes and many LED lamps flicker at twice the mains frequency (100 or 120 Hz) with a depth of a few per
cent (electronic ballasts) to nearly all of their light (cheap LED drivers); an LED dimmer switches at its PWM
frequency. A rolling shutter starts each row's exposure a little later than the last, so each row integrates another
part of the cycle: the frame is crossed by bands `height / (f * readout)` rows apart. An exposure of E seconds
averages the flicker over E, which leaves `|sinc(f E)|` of a sine's depth: none at 10 ms (one cycle at 100 Hz), most
of it in the short exposures of a bright room. From frame to frame the bands move on by `f / fps` cycles (at 100 Hz
and 30 fps a third of a cycle; at 120 Hz and 30 fps they stand still).

Used by `bench/vision_bench.py --flicker` (one lamp drawn per frame) and `bench/vision_clips.py --flicker` (one lamp
per clip, its phase following each frame's time).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WAVES = ("sine", "pwm")


@dataclass(frozen=True)
class Lamp:
    """A flickering light and the camera's timing: `wave` "sine" (a tube's or a mains LED's ripple) or "pwm" (an LED
    dimmer's square wave, on for `duty` of each cycle); `f` Hz; `depth`, the share of its light the flicker takes at
    its lowest; `exposure` and `readout` (top row to bottom row) in seconds; `phase` at time 0, radians."""

    wave: str
    f: float
    exposure: float
    readout: float
    depth: float
    phase: float
    duty: float = 0.5

    def gain(self, rows: int, t: float = 0.0) -> np.ndarray:
        """Each row's light in a frame whose top row starts its exposure at `t` seconds (the mean light is 1)."""
        if self.wave == "sine":
            return 1.0 + self.amplitude() * np.sin(2 * np.pi * self.f * (self.readout * np.arange(rows) / rows + t)
                                                   + self.phase)
        starts = self.readout * np.arange(rows) / rows + self.phase / (2 * np.pi * self.f) + t
        samples = starts[:, None] + self.exposure * (np.arange(64) + 0.5)[None, :] / 64  # each row's exposure
        light = np.where((samples * self.f) % 1.0 < self.duty, 1.0, 1.0 - self.depth).mean(axis=1)
        return light / light.mean()

    def amplitude(self, rows: int = 480) -> float:
        """(brightest - darkest) / (brightest + darkest) of a frame's rows' light: a sine's own depth, attenuated."""
        if self.wave == "sine":
            return self.depth * abs(float(np.sinc(self.f * self.exposure)))
        g = self.gain(rows)
        return float((g.max() - g.min()) / (g.max() + g.min()))


def draw_lamp(rng: np.random.Generator, depth: float, wave: str = "sine") -> Lamp:
    """A lamp: 100 or 120 Hz for a sine, 100-1,000 Hz on for 20-80 % of each cycle for PWM; its depth `depth` x
    U(0.5, 1); an exposure of 1-8 ms, a readout of 15-33 ms and a phase."""
    if wave not in WAVES:
        raise ValueError(f"flicker wave must be sine or pwm, got {wave!r}")
    f = float(rng.choice((100.0, 120.0))) if wave == "sine" else rng.uniform(100.0, 1000.0)
    exposure, readout = rng.uniform(0.001, 0.008), rng.uniform(0.015, 0.033)
    light_depth = depth * rng.uniform(0.5, 1.0)
    phase = rng.uniform(0, 2 * np.pi)
    duty = rng.uniform(0.2, 0.8) if wave == "pwm" else 0.5
    return Lamp(wave, f, exposure, readout, light_depth, phase, duty)


def lit(img: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """`img` (uint8) with each row's light multiplied by `gain`, in linear light (gamma 2.2), clipped."""
    linear = (img.astype(np.float32) / 255.0) ** 2.2
    linear *= gain.astype(np.float32).reshape((-1,) + (1,) * (img.ndim - 1))
    return np.round(np.clip(linear, 0.0, 1.0) ** (1 / 2.2) * 255.0).astype(np.uint8)


def flicker_bands(img: np.ndarray, rng: np.random.Generator, depth: float, wave: str = "sine") -> tuple[np.ndarray, float]:
    """`img` under a lamp drawn for it (`draw_lamp`), and the bands' amplitude (`Lamp.amplitude`)."""
    lamp = draw_lamp(rng, depth, wave)
    return lit(img, lamp.gain(img.shape[0])), lamp.amplitude(img.shape[0])
