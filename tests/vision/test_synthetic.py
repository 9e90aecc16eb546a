"""The tuning generator's coverage of what a real camera does: fingers over the mark, pale ink."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.synthetic import MILD, SceneGenerator, Sheen, Variation

SKIN = np.array([120, 150, 200])  # the fingers' BGR (their rim is darker)


def _skin_in_box(img: np.ndarray, box: tuple[int, int, int, int]) -> int:
    x, y, w, h = box
    patch = img[y : y + h, x : x + w].astype(np.int32)
    return int((np.abs(patch - SKIN).max(axis=2) < 25).sum())


def test_fingers_over_the_mark_cover_part_of_its_box() -> None:
    over = SceneGenerator(seed=4, variation=MILD.only(fingers=1.0, finger_over=1.0))
    near = SceneGenerator(seed=4, variation=MILD.only(fingers=1.0, finger_over=0.0))
    for _ in range(6):
        assert over.scene(Shape.O).finger_gap <= 0 < near.scene(Shape.O).finger_gap
    scene = over.scene(Shape.TRIANGLE)
    covered = []
    for gap in (0.1, -0.25):  # the same card, fingers stopping short of the mark or over its edge
        scene.finger_gap = gap
        img, labels = over.render(scene)
        covered.append(_skin_in_box(img, labels[0].box))
    assert covered[1] > covered[0] + 50


def test_pale_ink_is_lighter_but_keeps_the_scene() -> None:
    for seed in range(6):
        a = SceneGenerator(seed=seed, variation=MILD.only(pale_ink=1.0)).scene(Shape.X)
        b = SceneGenerator(seed=seed, variation=MILD.only(pale_ink=0.0)).scene(Shape.X)
        assert a.size == b.size and a.paper == b.paper  # the draws before the ink are unchanged
        assert sum(a.ink) > sum(b.ink)
        assert all(i <= p for i, p in zip(a.ink, a.paper, strict=True))


def _skin_side(img: np.ndarray, box: tuple[int, int, int, int], skin: tuple[int, int, int]) -> str:
    """Which side of the mark's box the pixels of this skin tone lie on, mostly."""
    ys, xs = np.nonzero(np.abs(img.astype(np.int32) - np.array(skin) - 25).max(axis=2) < 20)
    x, y, w, h = box
    dx, dy = float(np.median(xs)) - (x + w / 2), float(np.median(ys)) - (y + h / 2)
    return ("right" if dx > 0 else "left") if abs(dx) > abs(dy) else ("below" if dy > 0 else "above")


def test_varied_hands_have_any_skin_width_and_edge_and_leave_the_rest_of_the_scene() -> None:
    """`hand_variety`: people's fingers - dark to pale, narrow to wide, over any edge of the card."""
    varied = SceneGenerator(seed=7, variation=MILD.only(fingers=1.0, hand_variety=1.0))
    plain = SceneGenerator(seed=7, variation=MILD.only(fingers=1.0))
    scenes = [varied.scene(Shape.X) for _ in range(40)]
    first = plain.scene(Shape.X)
    assert (scenes[0].size, scenes[0].fingers, scenes[0].finger_gap) == (
        first.size,
        first.fingers,
        first.finger_gap,
    )
    assert (first.skin, first.finger_width, first.finger_edge) == ((95, 125, 175), 0.2, 0)
    assert {s.finger_edge for s in scenes} == {0, 1, 2, 3}
    tones = [sum(s.skin) / 3 for s in scenes]
    assert min(tones) < 90 and max(tones) > 160
    assert all(0.12 <= s.finger_width <= 0.45 for s in scenes)


def test_fingers_come_over_the_edge_they_are_given() -> None:
    gen = SceneGenerator(seed=3, variation=MILD.only(fingers=1.0))
    scene = gen.scene(Shape.O)
    scene.skin, scene.finger_width, scene.finger_gap = (60, 80, 120), 0.3, 0.1
    sides = []
    for edge in range(4):  # quarter turns from the bottom, counter-clockwise: bottom, right, top, left
        scene.finger_edge = edge
        img, labels = gen.render(scene)
        sides.append(_skin_side(img, labels[0].box, scene.skin))
    assert len(set(sides)) == 4 and sides[0] == "below"


def _ink_box(img: np.ndarray, near: tuple[int, int, int, int], pad: int = 12) -> tuple[int, int, int, int]:
    """The box round the darkest pixels (the mark's ink) within `pad` of the box `near`."""
    x, y, w, h = near
    x0, y0 = max(0, x - pad), max(0, y - pad)
    grey = img[y0 : y + h + pad, x0 : x + w + pad].astype(np.int32).mean(axis=2)
    ys, xs = np.nonzero(grey < grey.min() + 0.4 * (np.median(grey) - grey.min()))
    return (x0 + int(xs.min()), y0 + int(ys.min()), int(xs.max() - xs.min()), int(ys.max() - ys.min()))


def test_a_wide_angle_lens_moves_the_mark_and_its_label_with_it() -> None:
    """`lens`: barrel distortion (corners fixed, the middle magnified); the label's box is where the
    mark's ink ends up. The lens draws nothing: the scenes are those of the same seed without it."""
    plain = SceneGenerator(seed=5, variation=MILD.only(fingers=0.0))
    lensed = SceneGenerator(seed=5, variation=MILD.only(fingers=0.0, lens=0.4))
    for _ in range(3):
        a, b = plain.scene(Shape.X), lensed.scene(Shape.X)
        assert (a.size, a.center, a.ink, a.lens) == (b.size, b.center, b.ink, 0.0) and b.lens == 0.4
    a.blur, a.noise, a.jpeg, a.center = (0.0, 0.0), 0.0, 0, (500.0, 140.0)  # sharp, off-centre
    boxes = []
    for k in (0.0, 0.4):
        a.lens = k
        img, labels = plain.render(a)
        ink = _ink_box(img, labels[0].box)
        slack = max(
            4, 0.04 * max(labels[0].box[2:])
        )  # the nine points' box is a little generous on a bent mark
        assert all(abs(p - q) <= slack for p, q in zip(ink, labels[0].box, strict=True)), (
            k,
            ink,
            labels[0].box,
        )
        boxes.append(labels[0].box)
    (x0, y0, _, _), (x1, y1, _, _) = boxes
    assert x1 > x0 + 5 and y1 < y0 - 5  # pushed out towards the top-right corner it lies towards


def test_the_lens_has_a_calibration_in_opencvs_model_that_straightens_it() -> None:
    """`lens_calibration`: OpenCV's radial model fitted to the lens; undistorting a lensed frame with it
    gives the lens-free frame as the undistorted camera sees it (`vision_bench.py --lens K --calibrated`)."""
    from services.vision.calibration import Undistorter
    from services.vision.synthetic import lens_calibration

    plain = SceneGenerator(seed=5, variation=MILD.only(fingers=0.0))
    scene = plain.scene(Shape.X)
    scene.blur, scene.noise, scene.jpeg, scene.center = (0.0, 0.0), 0.0, 0, (420.0, 200.0)
    pinhole, _ = plain.render(scene)
    scene.lens = 0.3
    seen, _ = plain.render(scene)
    undistort = Undistorter(lens_calibration(0.3, 640, 480))
    new = undistort.new_matrix(640, 480)
    f = 320.0  # the pinhole scene's focal length (half the width)
    affine = np.array([[new[0, 0] / f, 0, new[0, 2] - new[0, 0] / f * 320], [0, new[1, 1] / f, new[1, 2] - new[1, 1] / f * 240]])
    expected = cv2.warpAffine(pinhole, affine, (640, 480), borderMode=cv2.BORDER_REPLICATE)
    inner = (slice(40, 440), slice(40, 600))
    before = np.abs(seen[inner].astype(int) - expected[inner]).mean()
    after = np.abs(undistort(seen)[inner].astype(int) - expected[inner]).mean()
    assert after < 0.2 * before, (before, after)


def test_arrows_are_drawn_only_when_asked_and_unknown_clutter_is_refused() -> None:
    """An arrow (round vision21) is clutter the default generator never draws (its frames stay those of every
    seed before); asked for, it is ink on the scene with a filled triangular head."""
    default = SceneGenerator(seed=5, variation=MILD, use_skimage=False)
    assert "arrow" not in default.variation.kinds
    arrows = SceneGenerator(seed=5, variation=MILD.only(kinds=("arrow",)), use_skimage=False)
    drawn = 0
    for _ in range(10):
        img = np.full((arrows.height, arrows.width, 3), 128, np.uint8)
        arrows._distractor(img, "arrow")
        drawn += int((np.abs(img.astype(int) - 128).max(axis=2) > 40).sum() > 50)  # a label or ink, not a speck
    assert drawn >= 8  # some fall mostly outside the frame
    with pytest.raises(ValueError, match="unknown clutter kind 'kite'"):
        SceneGenerator(seed=5, variation=Variation(kinds=("kite",)), use_skimage=False).frame(None)


def test_marks_drawn_by_hand_keep_the_scene_and_their_box_holds_the_ink() -> None:
    """`hand_drawn` (round vision22): a mark drawn with a pen - uneven, wavering, round-ended - in the same scene
    as the exact mark; the label's box holds its ink. At 0 nothing is drawn from the random stream, so every
    seed's scenes stay those of before."""
    assert all(SceneGenerator(seed=s, variation=MILD).scene(Shape.X).by_hand is None for s in range(4))
    for seed in range(9):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE)[seed % 3]
        exact = SceneGenerator(seed=seed, variation=MILD.only(noise=0.0))
        by_hand = SceneGenerator(seed=seed, variation=MILD.only(noise=0.0, hand_drawn=1.0))
        a, b = exact.scene(shape), by_hand.scene(shape)
        assert (a.size, a.center, a.ink) == (b.size, b.center, b.ink) and b.by_hand is not None
        img_a, lab_a = exact.render(a)
        img_b, lab_b = by_hand.render(b)
        b.ink = b.paper  # the same scene with the mark in the paper's colour: the difference is its ink
        blank, _ = by_hand.render(b)
        # (dark: the hand holding the card's corner is drawn anew at each render, in skin tones)
        mark_ink = (np.abs(img_b.astype(int) - blank).max(axis=2) > 30) & (img_b.max(axis=2) < 110)
        x, y, w, h = lab_b[0].box
        inside = mark_ink[y : y + h, x : x + w].sum()
        assert inside >= 0.97 * mark_ink.sum(), (shape, inside, mark_ink.sum())
        assert np.abs(img_a.astype(int) - img_b).max(axis=2).astype(bool).sum() > 100  # another drawing
        assert abs(lab_a[0].box[2] - w) < 0.35 * w  # about the same size


def test_hand_drawn_shapes_limit_the_pen_to_those_shapes() -> None:
    """`hand_drawn_shapes` (round vision22c): only marks of those shapes are drawn by hand; the others keep the
    exact drawing, and the scenes' other draws are unchanged."""
    only_triangles = MILD.only(hand_drawn=1.0, hand_drawn_shapes=(Shape.TRIANGLE,))
    for seed in range(4):
        every = SceneGenerator(seed=seed, variation=MILD.only(hand_drawn=1.0))
        some = SceneGenerator(seed=seed, variation=only_triangles)
        for shape in (Shape.X, Shape.O, Shape.TRIANGLE):
            a, b = every.scene(shape), some.scene(shape)
            assert (a.size, a.center, a.ink) == (b.size, b.center, b.ink)
            assert (b.by_hand is not None) == (shape is Shape.TRIANGLE) and a.by_hand is not None


@pytest.mark.parametrize("kind", ["star", "check", "clock"])
def test_everyday_pictograms_are_drawn_only_when_asked(kind: str) -> None:
    """Stars, check marks and clock faces (round vision23) are clutter the default generator never draws; asked for,
    each is ink on the scene (on a light plate 70 % of the time), never a label."""
    assert kind not in SceneGenerator(seed=5, variation=MILD, use_skimage=False).variation.kinds
    gen = SceneGenerator(seed=5, variation=MILD.only(kinds=(kind,)), use_skimage=False)
    drawn = 0
    for _ in range(10):
        img = np.full((gen.height, gen.width, 3), 128, np.uint8)
        gen._distractor(img, kind)
        drawn += int((np.abs(img.astype(int) - 128).max(axis=2) > 40).sum() > 50)
    assert drawn >= 8
    _, labels = gen.frame(None)
    assert labels == []


def test_crossing_strokes_are_drawn_only_when_asked_and_run_on_past_the_crossing() -> None:
    """"crossing" (round vision45): strokes crossing at the clutter's point, the kind stop 78 found the proposer taking
    for an X. The default generator never draws it; asked for, there is ink at the point, and the ink runs on at least
    twice the clutter's size from it (two short strokes crossing would be an X, drawn without its card)."""
    from services.vision import synthetic

    assert "crossing" not in SceneGenerator(seed=5, variation=MILD, use_skimage=False).variation.kinds
    rng = np.random.default_rng(9)
    for size in (20.0, 40.0, 60.0, 20.0, 30.0, 50.0):
        img = np.full((1200, 1200, 3), 128, np.uint8)
        synthetic._draw_crossing(img, rng, 600.0, 600.0, size)
        ink = np.abs(img.astype(int) - 128).max(axis=2) > 0
        assert ink[597:604, 597:604].any()
        ys, xs = np.nonzero(ink)
        assert np.hypot(xs - 600, ys - 600).max() >= 2 * size


def test_a_glossy_cards_sheen_keeps_the_scene_and_lightens_the_ink_under_it() -> None:
    """`sheen` (round vision66): a lamp's reflection on a glossy card, drawn last from the random stream (at 0 nothing is
    drawn: every seed's scenes stay those of before), adds light over the mark's ink and the paper alike: under its
    flat middle the ink is lighter than the same scene's ink without it, and nothing off the card changes."""
    assert all(SceneGenerator(seed=s, variation=MILD).scene(Shape.X).sheen is None for s in range(4))
    lighter = 0
    for seed in range(6):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE)[seed % 3]
        matte = SceneGenerator(seed=seed, variation=MILD.only(noise=0.0))
        glossy = SceneGenerator(seed=seed, variation=MILD.only(noise=0.0, sheen=1.0))
        a, b = matte.scene(shape), glossy.scene(shape)
        assert (a.size, a.center, a.ink, a.paper) == (b.size, b.center, b.ink, b.paper) and b.sheen is not None
        b.sheen = replace(b.sheen, peak=0.5, offset=(0.0, 0.0), length=0.0, radius=0.6, soft=0.1)  # over the whole mark
        img_a, lab = matte.render(a)
        img_b, _ = glossy.render(b)
        a.ink = a.paper
        blank, _ = matte.render(a)
        x, y, w, h = lab[0].box
        ink = (np.abs(img_a.astype(int) - blank).max(axis=2) > 40)[y : y + h, x : x + w]
        ink_a = img_a[y : y + h, x : x + w][ink].mean()
        ink_b = img_b[y : y + h, x : x + w][ink].mean()
        lighter += ink_b > ink_a + 40  # half of white added in linear light lifts dark ink by over 150 grey levels
        off_card = np.abs(img_a.astype(int) - img_b).max(axis=2) == 0
        assert off_card.mean() > 0.5  # the background and clutter are the same
    assert lighter == 6


def test_sheen_shapes_keeps_the_other_marks_cards_matte_and_every_scene_as_it_was() -> None:
    """`sheen_shapes` (round vision67): only the cards of those marks are glossy; the sheen is drawn for every card,
    so a scene's size, place, ink and paper are those of the same seed with the sheen on every card."""
    for seed in range(6):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE)[seed % 3]
        every = SceneGenerator(seed=seed, variation=MILD.only(sheen=1.0)).scene(shape)
        danger = SceneGenerator(
            seed=seed, variation=MILD.only(sheen=1.0, sheen_shapes=(Shape.X, Shape.TRIANGLE))
        ).scene(shape)
        assert (every.size, every.center, every.ink) == (danger.size, danger.center, danger.ink)
        assert every.paper == danger.paper
        assert every.sheen is not None
        assert danger.sheen == (None if shape is Shape.O else every.sheen)


def test_a_sheens_light_is_flat_inside_and_falls_to_nothing_beyond_its_edge() -> None:
    """`Sheen.light`: `peak` along its segment and within `radius` of it, 0 beyond `radius + soft`, in between less."""
    sheen = Sheen(offset=(0.0, 0.0), length=1.0, radius=0.1, soft=0.2, angle=0.0, peak=0.8)
    light = sheen.light((200, 400), (200.0, 100.0), 100.0)  # the mark 100 px wide, centred at (200, 100)
    assert light[100, 200] == pytest.approx(0.8) and light[100, 245] == pytest.approx(0.8)  # on the segment
    assert light[100, 255] == pytest.approx(0.8)  # 5 px beyond its end: within the radius
    assert light[135, 200] == 0.0 and light[100, 281] == 0.0  # 0.35 widths off it, 0.31 beyond its end
    assert 0.0 < light[120, 200] < 0.8  # in its soft edge
