"""The tuning generator's coverage of what a real camera does: fingers over the mark, pale ink."""

from __future__ import annotations

import numpy as np

from schemas.messages import Shape
from services.vision.synthetic import MILD, SceneGenerator

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
