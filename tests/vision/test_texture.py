"""The card test's plainness against the card's own local mean (`DetectorConfig.texture_window`, round vision71): light
that changes smoothly across a card is not texture, gravel's grain still is."""

from __future__ import annotations

import numpy as np
import pytest

from bench.glare import glare_spot
from bench.vision_bench import _generator
from schemas.messages import Shape
from services.vision.detector import MarkDetector, _local_spread, box_overlap, parse_settings
from services.vision.verifier import CLASSES


def test_a_smooth_lobe_has_little_local_spread_and_grain_keeps_its_own() -> None:
    ys, xs = np.mgrid[0:120, 0:160].astype(np.float32)
    lobe = 150.0 + 80.0 * np.exp(-((xs - 60) ** 2 + (ys - 50) ** 2) / (2 * 30.0**2))  # a highlight on a card
    mask = np.zeros((120, 160), np.uint8)
    mask[10:110, 10:150] = 255
    mask[45:75, 65:95] = 0  # the mark's place: not card
    grain = np.random.default_rng(1).normal(0.0, 12.0, lobe.shape)
    smooth, gravel = lobe.astype(np.uint8), np.clip(150.0 + grain, 0, 255).astype(np.uint8)
    plain = float(smooth[mask > 0].std())
    assert plain > 15.0  # the plain measure: far from plain
    assert _local_spread(smooth, mask, 15) < 0.15 * plain
    assert _local_spread(gravel, mask, 15) > 0.9 * float(gravel[mask > 0].std())  # grain finer than the window stays


def _bench_glare_frame(seed: int, i: int) -> tuple[np.ndarray, tuple[Shape, tuple[int, int, int, int]]]:
    """Frame `i` of tuning seed `seed` as `bench/vision_bench.py --glare 1` draws it: the bench's generator, one class
    a frame in turn, and its highlight at a peak of white from the bench's own draws."""
    frame_of = _generator("tuning", seed)
    for k in range(i + 1):
        img, label, _ = frame_of(CLASSES[k % len(CLASSES)])
    img, _ = glare_spot(img, np.random.default_rng((seed, i, 1)), 1.0, label[1])
    return img, label


def _finds(img: np.ndarray, label: tuple[Shape, tuple[int, int, int, int]], settings: list[str]) -> bool:
    """Whether the detector with `settings` finds the labelled mark: its shape, at least half its box."""
    dets = MarkDetector(parse_settings(settings)).detect(img)
    return any(d.shape is label[0] and box_overlap(d.box, label[1]) >= 0.5 for d in dets)


def test_an_x_under_a_highlight_refused_as_texture_is_found_with_the_window() -> None:
    """Tuning seed 7263's frame 24 under bench/glare.py's highlight at a peak of white: a big X whose card the
    highlight brightens at one arm. The plain measure refuses its card as texture; with the window (the default for a
    danger mark since round vision71c) the X is found."""
    img, label = _bench_glare_frame(7263, 24)
    assert label[0] is Shape.X
    assert not any(d.shape is Shape.X for d in MarkDetector(parse_settings(["danger_texture_window=0"])).detect(img))
    for settings in (["texture_window=0.5", "danger_texture_window=0"], []):  # every card's window; the default's
        assert _finds(img, label, settings)


def test_the_window_is_a_share_of_the_extent() -> None:
    # every card's window off (round vision71's false O), a danger mark's at half the extent (round vision71c)
    assert (parse_settings([]).texture_window, parse_settings([]).danger_texture_window) == (0.0, 0.5)
    assert parse_settings([]).safe_texture_window == 0.5  # an O's, guarded by the verifier (round vision72)
    for bad in ("texture_window=-0.5", "danger_texture_window=5", "safe_texture_window=9"):
        with pytest.raises(ValueError, match="texture_window"):
            parse_settings([bad])


def test_the_danger_window_leaves_an_o_to_the_plain_measure(monkeypatch: pytest.MonkeyPatch) -> None:
    """`danger_texture_window` measures an X's or a triangle's card against its local mean, never an O's (round
    vision71b): the window each card test asks for, by the mark's kind."""
    import services.vision.detector as detector

    asked: list[int] = []
    spread = detector._local_spread

    def recorded(g: np.ndarray, mask: np.ndarray, window: int) -> float:
        asked.append(window)
        return spread(g, mask, window)

    monkeypatch.setattr(detector, "_local_spread", recorded)
    ys, xs = np.mgrid[0:120, 0:160].astype(np.float32)  # grey ink on a card, a highlight by its corner
    card = np.clip(140.0 + 100.0 * np.exp(-((xs - 95) ** 2 + (ys - 45) ** 2) / (2 * 12.0**2)), 0, 255).astype(np.uint8)
    filled = np.zeros_like(card)
    filled[50:70, 70:90] = 255
    card[filled > 0] = 80
    dist = detector._distance(filled, (70, 50, 20, 20), 200.0)
    cfg = parse_settings(["danger_texture_window=0.5"])
    o = detector._on_card(card, filled, 80.0, 20.0, dist, cfg, may_rescue=False, danger=False)
    assert o == "texture" and asked == []  # an O: the plain measure alone, which the highlight fails
    x = detector._on_card(card, filled, 80.0, 20.0, dist, cfg, may_rescue=False, danger=True)
    assert asked == [10] and x != "texture"  # an X: measured again with the window (half the extent), and passed


def test_an_o_kept_by_its_window_needs_the_verifier_sure() -> None:
    """Tuning seed 7263's frame 373 under the bench's highlight: an O whose card the plain measure refuses as texture.
    `safe_texture_window` measures it against its local mean and keeps it, for an O only with the verifier's
    `safe_card_sure` (round vision72, the default since stop 118): asked for a certainty no network gives, it is
    refused again."""
    img, label = _bench_glare_frame(7263, 373)
    assert label[0] is Shape.O
    assert not _finds(img, label, ["safe_texture_window=0"])
    assert _finds(img, label, [])
    assert not _finds(img, label, ["safe_card_sure=1"])
