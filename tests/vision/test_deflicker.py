"""deflicker.py: the bands a flickering light draws across a rolling-shutter frame, found from the frame alone and
divided out; a frame without them is left as it is."""

from __future__ import annotations

import numpy as np
import pytest

from services.vision.deflicker import deflicker, find_bands


def _scene(seed: int = 0) -> np.ndarray:
    """A grey scene with its own edges: paper-light rectangles and dark strokes on a mid-grey wall, and sensor
    noise."""
    rng = np.random.default_rng(seed)
    img = np.full((480, 640), 120.0)
    for _ in range(12):
        x, y = rng.integers(0, 560), rng.integers(0, 400)
        w, h = rng.integers(40, 200), rng.integers(30, 160)
        img[y : y + h, x : x + w] = rng.uniform(60, 230)
    for _ in range(20):
        x, y = rng.integers(0, 600), rng.integers(0, 440)
        img[y : y + 40, x : x + 6] = rng.uniform(20, 60)
    return np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8)


def _banded(gray: np.ndarray, amplitude: float, period: float, phase: float = 0.3) -> np.ndarray:
    """Bands of `amplitude` (of linear light) every `period` rows, through a gamma of 2.2."""
    gain = 1.0 + amplitude * np.sin(2 * np.pi * np.arange(gray.shape[0]) / period + phase)
    linear = (gray / 255.0) ** 2.2 * gain[:, None]
    return np.clip(np.clip(linear, 0, 1) ** (1 / 2.2) * 255 + 0.5, 0, 255).astype(np.uint8)


def _band_swing(gray: np.ndarray, clean: np.ndarray) -> float:
    """Peak to peak of the log ratio of the rows' mean grey to the clean frame's: the bands left in `gray`."""
    ratio = np.log(gray.mean(axis=1) + 1.0) - np.log(clean.mean(axis=1) + 1.0)
    return float(np.ptp(ratio))


@pytest.mark.parametrize(("amplitude", "period", "left"), [
    (0.6, 150.0, 0.2), (0.8, 230.0, 0.2), (0.4, 60.0, 0.2), (0.3, 16.0, 0.3),
    (0.5, 320.0, 0.65),  # a cycle and a half a frame: the quadratic trend (the scene's shading) takes part of it
])
def test_bands_are_found_at_their_period_and_mostly_evened_out(amplitude: float, period: float, left: float) -> None:
    clean = _scene(1)
    banded = _banded(clean, amplitude, period)
    bands = find_bands(banded)
    assert bands.share > 0.9 and abs(bands.period - period) < 0.2 * period
    assert _band_swing(deflicker(banded), clean) < left * _band_swing(banded, clean)


def test_a_frame_without_bands_is_left_as_it_is() -> None:
    for seed in range(6):
        clean = _scene(seed)
        assert deflicker(clean) is clean  # nothing periodic in the rows of a scene's own edges


def test_a_frame_too_small_to_tell_is_left_as_it_is() -> None:
    small = _banded(_scene(2), 0.8, 150.0)[:48]
    assert deflicker(small) is small


def test_the_option_finds_danger_marks_the_bands_hid() -> None:
    """Tuning frames (seed 7222) under a cheap LED lamp's bands (bench/vision_bench.py --flicker 1.0): three danger
    marks the default misses there and finds without the bands; `deflicker=1` finds them through the bands."""
    from bench.flicker import flicker_bands
    from bench.vision_bench import CLASSES, _generator
    from services.vision.detector import MarkDetector, box_overlap, parse_settings

    frame_of = _generator("tuning", 7222)
    frames = {}
    for i in range(31):
        img, label, _ = frame_of(CLASSES[i % len(CLASSES)])
        if i in (20, 24, 30):
            frames[i] = (flicker_bands(img, np.random.default_rng((7222, i)), 1.0)[0], label)

    def found(detector: MarkDetector) -> int:
        return sum(any(d.shape == label[0] and box_overlap(d.box, label[1]) >= 0.5 for d in detector.detect(img))
                   for img, label in frames.values())

    assert found(MarkDetector(parse_settings(["deflicker=1"]))) - found(MarkDetector(parse_settings([]))) >= 2
