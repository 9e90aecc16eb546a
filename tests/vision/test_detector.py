"""The detector on generated frames: each variation alone, full clutter, non-marks, bad input."""

from __future__ import annotations

import dataclasses
import re
import zlib

import cv2
import numpy as np
import pytest
from PIL import Image, ImageDraw, ImageFont

import services.vision.detector as detector_module
from schemas.messages import Shape
from services.vision.detector import (
    Detection,
    DetectorConfig,
    MarkDetector,
    _in_text_line,
    box_overlap,
    changed_settings,
    parse_settings,
)
from services.vision.synthetic import MILD, SceneGenerator, Variation
from services.vision.verifier import CLASSES

SHAPES = (Shape.X, Shape.O, Shape.TRIANGLE)
PER_SHAPE = 8

VARIATIONS: dict[str, Variation] = {
    "clean": MILD,
    "rotation": MILD.only(rotation_deg=180.0),
    "tilt": MILD.only(tilt_deg=50.0, rotation_deg=180.0),
    "small": MILD.only(size=(26.0, 40.0)),
    "large": MILD.only(size=(250.0, 420.0)),
    "uneven_light": MILD.only(light=1.0, dim=(0.45, 1.1)),
    "motion_blur": MILD.only(blur=7.0),
    "noise": MILD.only(noise=12.0),
    "jpeg": MILD.only(jpeg=(30, 50)),
    "clutter": MILD.only(distractors=(5, 8)),
    # the conditions of issue #13, each alone
    "fingers_near_mark": MILD.only(fingers=1.0, border=(0.1, 0.4)),
    "coloured_ink": MILD.only(colour_ink=1.0),
    "filled_triangle": MILD.only(filled_triangle=1.0),
    "blur_20px": MILD.only(blur=20.0, size=(90.0, 200.0)),
    "under_over_exposure": MILD.only(dim=(0.35, 1.5), light=1.0),
    "jpeg_40_and_noise": MILD.only(jpeg=(40, 45), noise=12.0),
    "tilt_45": MILD.only(tilt_deg=45.0, rotation_deg=180.0),
    "fills_frame": MILD.only(size=(300.0, 430.0), border=(0.1, 0.3)),
    # drawn with a pen (round vision22): uneven, wavering, round-ended strokes; alone they are found, it is
    # together with blur, small size and fingers that they are lost (vision README, "Vision22")
    "drawn_by_hand": MILD.only(hand_drawn=1.0, rotation_deg=180.0),
    "drawn_by_hand_filled_triangle": MILD.only(hand_drawn=1.0, filled_triangle=1.0, rotation_deg=180.0),
}


@pytest.fixture(scope="module")
def detector() -> MarkDetector:
    return MarkDetector()


def _correct(found: list[Detection], shape: Shape, box: tuple[int, int, int, int]) -> bool:
    return any(d.shape == shape and box_overlap(d.box, box) >= 0.5 for d in found)


@pytest.mark.parametrize("name", list(VARIATIONS))
def test_each_variation_finds_every_shape(detector: MarkDetector, name: str) -> None:
    gen = SceneGenerator(seed=zlib.crc32(name.encode()) % 1000, variation=VARIATIONS[name])
    for shape in SHAPES:
        hits = 0
        for _ in range(PER_SHAPE):
            img, labels = gen.frame(shape)
            found = detector.detect(img)
            hits += _correct(found, shape, labels[0].box)
            # misclassified marks (stray detections elsewhere are the mark-free test's business)
            wrong = [d for d in found if d.shape != shape and box_overlap(d.box, labels[0].box) > 0.2]
            assert not wrong, f"{name}: {shape.value} mark also read as {wrong}"
        assert hits >= PER_SHAPE - 1, f"{name}: found {hits}/{PER_SHAPE} {shape.value} marks"


def test_narrow_card_border_next_to_the_mark(detector: MarkDetector) -> None:
    """A border of 5-10 % of the mark's width: an X almost always; a triangle whose base nearly
    touches the card's edge is missed about a third of the time (the narrow band beside it is then
    partly background): a known limit. An O needs a clear margin of 10 % of its size on purpose (a
    false O lifts a danger), so on these cards it is found only when the border is wide enough."""
    gen = SceneGenerator(seed=zlib.crc32(b"narrow_border") % 1000, variation=MILD.only(border=(0.05, 0.1)))
    want = {Shape.X: PER_SHAPE - 1, Shape.O: PER_SHAPE - 4, Shape.TRIANGLE: PER_SHAPE - 3}
    for shape in SHAPES:
        hits = sum(
            _correct(detector.detect(img), shape, labels[0].box)
            for img, labels in (gen.frame(shape) for _ in range(PER_SHAPE))
        )
        assert hits >= want[shape], f"narrow border: found {hits}/{PER_SHAPE} {shape.value} marks"


def test_held_out_generator_frames_are_labelled_and_mostly_found(detector: MarkDetector) -> None:
    """The independent generator: deterministic, its labels inside the frame, and the detector finds
    most of its marks (a regression guard; the figures come from bench/vision_bench.py)."""
    from services.vision.heldout import HeldOutGenerator

    a, b = HeldOutGenerator(seed=3), HeldOutGenerator(seed=3)
    hits = total = 0
    for i in range(24):
        shape = SHAPES[i % 3]
        img, label = a.frame(shape)
        img2, label2 = b.frame(shape)
        # same seed, same frame, pixel for pixel (a background drawn at random, skimage's
        # binary_blobs without a seed, once made the held-out set differ from run to run)
        assert label2 == label and img.shape == (480, 640, 3)
        assert np.array_equal(img, img2)
        assert label is not None and label.shape is shape
        x, y, w, h = label.box
        assert 0 <= x and 0 <= y and x + w <= 640 and y + h <= 480 and min(w, h) >= 8
        hits += _correct(detector.detect(img), shape, label.box)
        total += 1
    assert hits >= total // 2, f"held-out: {hits}/{total}"


def test_mark_free_cluttered_frames_give_no_marks(detector: MarkDetector) -> None:
    gen = SceneGenerator(seed=11, variation=Variation(distractors=(4, 8)))
    frames = 60
    false = sum(bool(detector.detect(gen.frame(None)[0])) for _ in range(frames))
    assert false <= 2, f"{false}/{frames} mark-free frames produced a mark"


def test_procedural_backgrounds_without_scikit_image(detector: MarkDetector) -> None:
    gen = SceneGenerator(seed=3, variation=MILD.only(distractors=(2, 5)), use_skimage=False)
    assert not gen.bank
    img, labels = gen.frame(Shape.TRIANGLE)
    assert _correct(detector.detect(img), Shape.TRIANGLE, labels[0].box)


def _card(draw: str) -> np.ndarray:
    """A white card on grey with one non-mark (or mark) drawn in the middle."""
    img = np.full((480, 640, 3), 110, np.uint8)
    cv2.rectangle(img, (170, 90), (470, 390), (235, 235, 235), -1)
    ink = (30, 30, 30)
    if draw == "square":
        cv2.rectangle(img, (250, 170), (390, 310), ink, 18)
    elif draw == "filled_square":
        cv2.rectangle(img, (250, 170), (390, 310), ink, -1)
    elif draw == "disc":
        cv2.circle(img, (320, 240), 70, ink, -1, cv2.LINE_AA)
    elif draw == "filled_triangle":
        cv2.fillPoly(img, [np.array([[320, 170], [390, 300], [250, 300]], np.int32)], ink, cv2.LINE_AA)
    elif draw == "word":
        cv2.putText(img, "OXAO", (190, 260), cv2.FONT_HERSHEY_SIMPLEX, 2.6, ink, 9, cv2.LINE_AA)
    elif draw == "ring":
        cv2.circle(img, (320, 240), 60, ink, 18, cv2.LINE_AA)
    elif draw == "cross":
        cv2.line(img, (260, 180), (380, 300), ink, 20, cv2.LINE_AA)
        cv2.line(img, (380, 180), (260, 300), ink, 20, cv2.LINE_AA)
    return img


@pytest.mark.parametrize("draw", ["square", "filled_square", "disc", "word"])
def test_non_marks_on_a_card_are_rejected(detector: MarkDetector, draw: str) -> None:
    assert detector.detect(_card(draw)) == []


def test_a_filled_triangle_on_a_card_is_a_triangle_mark(detector: MarkDetector) -> None:
    found = detector.detect(_card("filled_triangle"))
    assert [d.shape for d in found] == [Shape.TRIANGLE]


@pytest.mark.parametrize(("draw", "shape"), [("ring", Shape.O), ("cross", Shape.X)])
def test_drawn_marks_on_a_card_are_found(detector: MarkDetector, draw: str, shape: Shape) -> None:
    found = detector.detect(_card(draw))
    assert [d.shape for d in found] == [shape]
    x, y, w, h = found[0].box
    assert abs(x + w / 2 - 320) < 8 and abs(y + h / 2 - 240) < 8
    assert 0.5 <= found[0].confidence <= 1.0


def _cross_on(paper: np.ndarray, ink: int) -> np.ndarray:
    """A bar cross of grey level `ink` over the grey `paper` (float, 480x640), as a BGR frame."""
    bars = np.zeros((480, 640), np.uint8)
    cv2.line(bars, (260, 180), (380, 300), 255, 20, cv2.LINE_AA)
    cv2.line(bars, (380, 180), (260, 300), 255, 20, cv2.LINE_AA)
    a = bars / 255.0
    img = (paper * (1 - a) + ink * a).clip(0, 255).astype(np.uint8)
    return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)


def test_a_faint_cross_is_not_a_mark(detector: MarkDetector) -> None:
    # darker than its surroundings by less than `min_contrast` grey levels: a shadow or a crease in
    # a texture, not print (the old rule, ink below 0.72 of the margin, let it through)
    faint = _cross_on(np.full((480, 640), 70.0), ink=48)
    assert detector.detect(faint) == []
    assert [d.shape for d in MarkDetector(DetectorConfig(min_contrast=0)).detect(faint)] == [Shape.X]
    assert [d.shape for d in detector.detect(_cross_on(np.full((480, 640), 100.0), ink=55))] == [Shape.X]


def test_a_mark_under_dim_light_is_found(detector: MarkDetector) -> None:
    # dim paper (grey 100) and ink 30 levels darker: print, though below the old 35-level limit
    dim = _cross_on(np.full((480, 640), 100.0), ink=70)
    assert [d.shape for d in detector.detect(dim)] == [Shape.X]
    assert MarkDetector(DetectorConfig(min_contrast=35)).detect(dim) == []


def _pale(shape: Shape, ink: float = 180.0) -> np.ndarray:
    """A mark in pale ink on a white card on grey: 60 grey levels under the paper (clearly print, not a
    shadow) but above 0.72 of it, so the card tests' contrast ratio refuses it."""
    stroke = np.zeros((480, 640), np.uint8)
    if shape is Shape.X:
        cv2.line(stroke, (260, 180), (380, 300), 255, 20, cv2.LINE_AA)
        cv2.line(stroke, (380, 180), (260, 300), 255, 20, cv2.LINE_AA)
    elif shape is Shape.TRIANGLE:
        corners = np.array([[320, 180], [380, 300], [260, 300]], np.int32)
        cv2.polylines(stroke, [corners], True, 255, 16, cv2.LINE_AA)
    else:
        cv2.circle(stroke, (320, 240), 60, 255, 18, cv2.LINE_AA)
    paper = np.full((480, 640), 90.0)
    paper[90:390, 170:470] = 240.0
    a = stroke / 255.0
    return cv2.cvtColor((paper * (1 - a) + ink * a).astype(np.uint8), cv2.COLOR_GRAY2BGR)


@pytest.mark.parametrize("shape", [Shape.X, Shape.TRIANGLE])
def test_a_pale_danger_mark_is_kept_on_the_verifiers_word(detector: MarkDetector, shape: Shape) -> None:
    frame = _pale(shape)
    assert MarkDetector(DetectorConfig(card_rescue=0)).detect(frame) == []  # the card tests refuse it
    assert [d.shape for d in detector.detect(frame)] == [shape]  # the verifier is sure: rescued


@pytest.mark.parametrize("shape", [Shape.X, Shape.O, Shape.TRIANGLE])
def test_danger_contrast_ratio_lets_light_ink_stop_the_robot_but_not_lift_a_danger(shape: Shape) -> None:
    """Round vision59b: `danger_contrast_ratio` 0.8 takes an X or a triangle in ink 60 grey levels under a white card
    but above 0.72 of it (pink, orange, pale tape, in grey) for a mark on the card tests' word alone (no rescue),
    while an O in it is still refused (`max_contrast_ratio` 0.72) and ink above 0.8 of the paper still is for all
    three. Out-of-range values are refused."""
    plain = DetectorConfig(card_rescue=0)
    danger = dataclasses.replace(plain, danger_contrast_ratio=0.8)
    light = _pale(shape)
    assert MarkDetector(plain).detect(light) == []
    assert [d.shape for d in MarkDetector(danger).detect(light)] == ([] if shape is Shape.O else [shape])
    assert MarkDetector(danger).detect(_pale(shape, ink=205.0)) == []
    for bad in (-0.1, 1.0):
        with pytest.raises(ValueError, match="danger_contrast_ratio"):
            DetectorConfig(danger_contrast_ratio=bad)


def test_a_pale_o_is_never_rescued(detector: MarkDetector) -> None:
    # the same pale ink as a ring: a false O lifts a danger, so the card tests' word stands for an O
    assert detector.detect(_pale(Shape.O)) == []


def test_a_faint_cross_or_a_letter_in_a_word_is_not_rescued(detector: MarkDetector) -> None:
    faint = _cross_on(np.full((480, 640), 70.0), ink=48)
    card = np.full((480, 640, 3), 110, np.uint8)
    cv2.rectangle(card, (100, 90), (540, 390), (235, 235, 235), -1)
    cv2.putText(card, "BOX", (130, 270), cv2.FONT_HERSHEY_SIMPLEX, 2.6, (30, 30, 30), 9, cv2.LINE_AA)
    word = cv2.warpAffine(  # an angle at which the network is sure of the word's X
        card, cv2.getRotationMatrix2D((320, 240), 285, 1.0), (640, 480), borderValue=(110,) * 3
    )
    assert detector.detect(faint) == [] and detector.detect(word) == []
    # the network alone would take both for an X: only the two tests it may not overrule hold them (the
    # word's X with the rescue at 0.6: the verifier retrained in round vision18b gives it 0.68, the one
    # before was sure of it)
    everything = DetectorConfig(card_rescue_from=(*DetectorConfig().card_rescue_from, "faint", "letter"))
    assert [d.shape for d in MarkDetector(everything).detect(faint)] == [Shape.X]
    assert MarkDetector(dataclasses.replace(DetectorConfig(), card_rescue=0.6)).detect(word) == []
    lenient = dataclasses.replace(everything, card_rescue=0.6, text_turned=False)
    assert [d.shape for d in MarkDetector(lenient).detect(word)] == [Shape.X]
    # since round vision20 the turned word is a line of letters, which no rescue overrules
    assert MarkDetector(dataclasses.replace(lenient, text_turned=True)).detect(word) == []


def test_a_bad_configuration_is_refused_at_construction() -> None:
    with pytest.raises(ValueError, match="unknown card tests"):
        MarkDetector(DetectorConfig(card_rescue_from=("band", "colour")))
    with pytest.raises(ValueError, match="bad pyramid level"):
        MarkDetector(DetectorConfig(levels=((1, 30),)))


def test_a_cross_in_a_busy_surround_is_not_a_mark() -> None:
    grain = np.random.default_rng(1).uniform(-50, 50, (480, 640))
    frame = _cross_on(200.0 + grain, ink=130)
    assert [d.shape for d in MarkDetector().detect(frame)] == [Shape.X]  # grain fine enough to pass
    # the same frame, judged with a plain-margin limit the grain's spread exceeds (and without the
    # verifier's rescue, which may overrule that limit for a danger mark it is sure of)
    assert MarkDetector(DetectorConfig(max_margin_texture=0.05, card_rescue=0)).detect(frame) == []


def test_faces_are_not_marks(detector: MarkDetector) -> None:
    skimage_data = pytest.importorskip("skimage.data")
    face = cv2.cvtColor(np.asarray(skimage_data.astronaut()), cv2.COLOR_RGB2BGR)
    assert detector.detect(cv2.resize(face, (640, 480))) == []


def test_grey_and_bgra_images_work(detector: MarkDetector) -> None:
    img = _card("ring")
    assert [d.shape for d in detector.detect(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))] == [Shape.O]
    assert [d.shape for d in detector.detect(cv2.cvtColor(img, cv2.COLOR_BGR2BGRA))] == [Shape.O]


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((0, 0, 3), np.uint8),
        np.zeros((48, 64, 3), np.float32),
        np.zeros((48, 64, 2), np.uint8),
        "img",
    ],
)
def test_bad_images_raise_value_error(detector: MarkDetector, bad: object) -> None:
    with pytest.raises(ValueError):
        detector.detect(bad)  # type: ignore[arg-type]


def test_tiny_image_is_fine(detector: MarkDetector) -> None:
    assert detector.detect(np.full((8, 8, 3), 200, np.uint8)) == []


def test_high_resolution_frames_are_scaled_and_boxes_mapped_back(detector: MarkDetector) -> None:
    """A 1920x1440 frame with a mark filling most of it: found, box in the input's pixels."""
    big = cv2.resize(_card("ring"), (1920, 1440), interpolation=cv2.INTER_CUBIC)
    found = detector.detect(big)
    assert [d.shape for d in found] == [Shape.O]
    x, y, w, h = found[0].box
    assert abs(x + w / 2 - 960) < 20 and abs(y + h / 2 - 720) < 20 and 390 < w < 440


def test_trace_names_where_each_component_ends(detector: MarkDetector) -> None:
    """`trace` (bench/vision_stages.py): the ring is kept; a filled disc ends at the pre-filter at full
    resolution (too full) and, hollowed by the quarter-scale threshold, at the hole test; a square
    outline is not kept; and trace finds what detect finds."""
    found, traced = detector.trace(_card("ring"))
    assert found == detector.detect(_card("ring"))
    kept = [t for t in traced if t.stage == "kept"]
    assert kept and all(t.shape is Shape.O for t in kept)
    assert any(box_overlap(t.box, found[0].box) > 0.8 for t in kept)
    _, traced = detector.trace(_card("disc"))
    central = [t for t in traced if abs(t.box[0] + t.box[2] / 2 - 320) < 10 and t.box[2] > 100]
    assert central and {"size/fill", "hole"} <= {t.stage for t in central}
    assert "kept" not in {t.stage for t in central}
    _, traced = detector.trace(_card("square"))
    central = [t for t in traced if abs(t.box[0] + t.box[2] / 2 - 320) < 10 and t.box[2] > 100]
    assert central and "kept" not in {t.stage for t in central}


def test_stage_accounting_charges_the_furthest_stage() -> None:
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from vision_stages import lost_at

    from services.vision.detector import Traced

    box = (100, 100, 50, 50)
    traced = [
        Traced((100, 100, 50, 50), None, "size/fill"),
        Traced((101, 99, 50, 52), Shape.X, "card"),  # the right box, taken for an X
        Traced((98, 100, 52, 50), Shape.O, "verifier"),
        Traced((300, 300, 50, 50), Shape.O, "kept"),  # elsewhere
    ]
    assert lost_at(traced, Shape.O, box) == "verifier"
    assert lost_at(traced, Shape.TRIANGLE, box) == "shape"  # a wrong shape is lost at the shape tests
    assert lost_at([], Shape.O, box) == "no component"
    # a loose candidate the verifier did not name got less far than one the shape tests claimed
    unnamed = [Traced((100, 100, 50, 50), Shape.O, "unnamed"), Traced((100, 100, 50, 50), None, "size/fill")]
    assert lost_at(unnamed, Shape.O, box) == "unnamed"
    assert lost_at([*unnamed, Traced((101, 99, 50, 52), Shape.O, "card")], Shape.O, box) == "card"
    # a mark the components lost but a confirmed proposal found is charged to the proposer; a detection
    # of another shape there, or of this shape elsewhere, is not that mark
    from vision_stages import charged

    from services.vision.detector import Detection

    assert charged([Detection(Shape.O, 0.995, (99, 101, 50, 49))], traced, Shape.O, box) == "proposed"
    assert charged([Detection(Shape.X, 0.9, box)], traced, Shape.O, box) == "verifier"
    assert charged([Detection(Shape.O, 0.9, (300, 300, 50, 50))], traced, Shape.O, box) == "verifier"
    kept = [*traced, Traced(box, Shape.O, "kept")]
    assert charged([Detection(Shape.O, 0.9, box)], kept, Shape.O, box) == "kept"


def _smeared_triangle(size: int = 30, blur: int = 13) -> np.ndarray:
    """A small triangle outline on a white card, smeared sideways by `blur` px of motion blur."""
    img = np.full((480, 640), 110, np.uint8)
    cv2.rectangle(img, (320 - size, 240 - size), (320 + size, 240 + size), 235, -1)
    s, t = size // 2, max(2, size // 7)
    angles = np.radians(90 + 120 * np.arange(3))
    pts = np.stack([320 + s * np.cos(angles), 240 + s * np.sin(angles)], axis=1).astype(np.int32)
    cv2.polylines(img, [pts], True, 30, t, cv2.LINE_AA)
    kernel = np.zeros((blur, blur), np.float32)
    kernel[blur // 2, :] = 1.0 / blur
    return cv2.filter2D(img, -1, kernel)


def test_a_loose_candidate_is_named_by_the_verifier(detector: MarkDetector) -> None:
    """Smeared, the triangle's hole is no triangle any more and the shape tests give up; as a loose
    candidate (dark on a light plain surround) the verifier names it, and the card tests still apply."""
    img = _smeared_triangle()
    _, traced = MarkDetector(DetectorConfig(loose=False)).trace(img)
    mine = [t for t in traced if abs(t.box[0] + t.box[2] / 2 - 320) < 8 and t.box[2] < 60]
    assert mine and "kept" not in {t.stage for t in mine} and "shape" in {t.stage for t in mine}
    found = detector.detect(img)
    assert [d.shape for d in found] == [Shape.TRIANGLE]
    assert found[0].confidence >= detector.verifier.loose_thresholds[2]  # type: ignore[union-attr]
    # nothing to name without the verifier, and a verifier that is never sure names nothing
    assert MarkDetector(DetectorConfig(verify=False)).detect(img) == []
    unsure = dataclasses.replace(detector.verifier, loose_thresholds=(1.01, 1.01, 1.01))  # type: ignore[arg-type]
    assert MarkDetector(DetectorConfig(propose=0.0), verifier=unsure).detect(img) == []
    # the trace (bench/vision_stages.py) ends that loose candidate at "unnamed", not at "verifier": the verifier was
    # asked to name a shape the shape tests did not claim, not to confirm one they did
    _, traced = MarkDetector(DetectorConfig(propose=0.0), verifier=unsure).trace(img)
    mine = {t.stage for t in traced if abs(t.box[0] + t.box[2] / 2 - 320) < 8 and t.box[2] < 60}
    assert "unnamed" in mine and not mine & {"verifier", "kept"}


def test_big_components_are_judged_at_the_quarter_scale_only() -> None:
    """`full_res_max`: a ring 240 px wide is not judged at full resolution (its card tests would
    cost 16 times as much there) but is still found, at the quarter-scale level."""
    img = np.full((480, 640, 3), 110, np.uint8)
    cv2.rectangle(img, (140, 60), (500, 420), (235, 235, 235), -1)
    cv2.circle(img, (320, 240), 110, (30, 30, 30), 30, cv2.LINE_AA)
    for limit, judged_full in ((160, False), (0, True)):
        det = MarkDetector(DetectorConfig(full_res_max=limit))
        found, traced = det.trace(img)
        assert [d.shape for d in found] == [Shape.O]
        full = {t.stage for t in traced if t.scale == 1 and t.box[2] > 200}
        quarter = {t.stage for t in traced if t.scale == 4 and t.box[2] > 200}
        assert "kept" in quarter
        assert (full == {"size/fill"}) != judged_full


# ---------------------------------------------------------------- marks joined to a finger (`_split`)
VISION15_LEVELS = ((1, 31), (2, 31, 50), (4, 31))  # the pyramid until round vision16
SKIN = (120, 140, 175)  # BGR, grey about 150: lighter than the ink, darker than the card
DARK_SKIN = (60, 80, 110)


def _finger(
    img: np.ndarray, centre: tuple[int, int], skin: tuple[int, int, int], angle: float = 0
) -> np.ndarray:
    """A finger (a filled ellipse 180 x 44 px) laid over the card."""
    out = img.copy()
    cv2.ellipse(out, centre, (90, 22), angle, 0, 360, skin, -1, cv2.LINE_AA)
    return out


def _outline_triangle() -> np.ndarray:
    img = _card("blank")
    cv2.polylines(
        img, [np.array([[320, 170], [390, 300], [250, 300]], np.int32)], True, (30, 30, 30), 16, cv2.LINE_AA
    )
    return img


@pytest.mark.parametrize(
    ("name", "shape"),
    [
        ("X, a finger over one arm", Shape.X),
        ("filled triangle, a dark finger touching it", Shape.TRIANGLE),
        ("triangle outline, a finger across its base", Shape.TRIANGLE),
    ],
)
def test_a_mark_joined_to_a_finger_is_cut_free(detector: MarkDetector, name: str, shape: Shape) -> None:
    img = {
        "X, a finger over one arm": lambda: _finger(_card("cross"), (400, 300), SKIN),
        "filled triangle, a dark finger touching it": lambda: _finger(
            _card("filled_triangle"), (420, 250), DARK_SKIN
        ),
        "triangle outline, a finger across its base": lambda: _finger(_outline_triangle(), (400, 300), SKIN),
    }[name]()
    # one joined shape that no test reads as a mark: on the pyramid before round vision16, whose coarser
    # levels (half resolution uncapped, a sixth) can read the X whole, finger and all, in a wider box
    premise = dataclasses.replace(detector.config, split="", levels=VISION15_LEVELS, propose=0.0)
    assert MarkDetector(premise).detect(img) == []
    # with `danger_first` (the default) the frame may end at a coarser level's X, finger and all (the robot
    # stops all the same): the shape is asserted there, the split's box without it
    assert [d.shape for d in detector.detect(img)] == [shape]
    found = MarkDetector(dataclasses.replace(detector.config, danger_first=False)).detect(img)
    assert [d.shape for d in found] == [shape]
    x, y, w, h = found[0].box
    assert (
        abs(x + w / 2 - 320) < 25 and abs(y + h / 2 - 240) < 25 and max(w, h) < 170
    )  # the mark, not the finger


def _held_from_above(draw: str, tip: tuple[int, int], skin: tuple[int, int, int]) -> np.ndarray:
    """`_card(draw)` with the card running on out of the frame's top, and a finger from above the frame
    down to `tip` (the hand holding the card is out of view)."""
    img = _card(draw)
    cv2.rectangle(img, (170, 0), (470, 90), (235, 235, 235), -1)
    cv2.line(img, (tip[0] + 30, -60), tip, skin, 40, cv2.LINE_AA)
    cv2.circle(img, tip, 20, skin, -1, cv2.LINE_AA)
    return img


@pytest.mark.parametrize("skin", [SKIN, DARK_SKIN])
def test_a_mark_joined_to_a_finger_from_out_of_the_frame_is_cut_free(
    detector: MarkDetector, skin: tuple[int, int, int]
) -> None:
    """A finger from above the frame over the end of an arm: X and finger are one component, cut by
    the frame edge, which only `split` with "edge" judges (its parts); then the X is found."""
    img = _held_from_above("cross", (380, 190), skin)
    assert MarkDetector(dataclasses.replace(detector.config, split="grey,loose", propose=0.0)).detect(img) == []
    found = MarkDetector(dataclasses.replace(detector.config, split="grey,loose,edge")).detect(img)
    assert [d.shape for d in found] == [Shape.X]
    x, y, w, h = found[0].box
    assert abs(x + w / 2 - 320) < 25 and abs(y + h / 2 - 240) < 25 and max(w, h) < 170


@pytest.mark.parametrize("draw", ["blank", "word", "square", "disc"])
def test_a_finger_from_out_of_the_frame_is_no_mark(detector: MarkDetector, draw: str) -> None:
    det = MarkDetector(dataclasses.replace(detector.config, split="grey,loose,edge"))
    for tip in [(440, 240), (380, 190), (320, 240), (250, 200)]:
        for skin in (SKIN, DARK_SKIN):
            assert det.detect(_held_from_above(draw, tip, skin)) == [], (tip, skin)


@pytest.mark.parametrize("draw", ["blank", "word", "square", "disc"])
def test_a_finger_on_a_card_or_touching_a_word_is_no_mark(detector: MarkDetector, draw: str) -> None:
    for centre in [(440, 240), (400, 300), (320, 240), (250, 200)]:
        for skin in (SKIN, DARK_SKIN):
            for angle in (0, 40, 90):
                assert detector.detect(_finger(_card(draw), centre, skin, angle)) == [], (centre, skin, angle)


# ---------------------------------------------------------------- the pyramid (`levels`)
def test_the_coarser_pyramid_finds_marks_the_old_one_missed_and_loses_none(detector: MarkDetector) -> None:
    """Round vision16: half resolution judges components of any size and a sixth-resolution level is
    added. On 200 tuning frames with varied hands it finds marks the old pyramid missed (four when it
    landed, three of them 140-240 px; one since round vision63c, whose O margin judged on the card lets the old
    pyramid find another), loses none the old one found, and adds no false mark."""
    old = MarkDetector(
        dataclasses.replace(detector.config, levels=VISION15_LEVELS), verifier=detector.verifier
    )
    gen = SceneGenerator(seed=555, variation=Variation(hand_variety=0.5))
    gained, lost, false_old, false_new = [], [], 0, 0
    for i in range(200):
        img, labels = gen.frame(CLASSES[i % len(CLASSES)])
        hits = []
        for det in (old, detector):
            found = det.detect(img)
            hit = [d for d in found if labels and _correct([d], labels[0].shape, labels[0].box)]
            hits.append(bool(hit))
            if det is old:
                false_old += len(found) - len(hit)
            else:
                false_new += len(found) - len(hit)
        if hits == [False, True]:
            gained.append(i)
        elif hits == [True, False]:
            lost.append(i)
    assert lost == [] and false_new <= false_old
    assert len(gained) >= 1, gained


# ---------------------------------------------------------------- settings (`--detector`, `HRI_VISION_DETECTOR`)
def test_detector_settings_are_parsed_by_type_and_bad_ones_named() -> None:
    cfg = parse_settings(
        "split= card_rescue=0.97;card_rescue_from=band,texture  loose=off split_share=0.1,0.02"
    )
    assert cfg.split == "" and cfg.card_rescue == 0.97 and cfg.loose is False
    assert cfg.card_rescue_from == ("band", "texture") and cfg.split_share == (0.1, 0.02)
    assert (
        dataclasses.replace(
            cfg,
            split=DetectorConfig().split,
            card_rescue=0.95,
            card_rescue_from=DetectorConfig().card_rescue_from,
            loose=True,
            split_share=DetectorConfig().split_share,
        )
        == DetectorConfig()
    )
    assert parse_settings("") == DetectorConfig() and parse_settings(["min_size=20"]).min_size == 20
    old_pyramid = parse_settings("levels=1:31,2:31:50,4:31")  # the pyramid before round vision16
    assert (
        old_pyramid.levels == VISION15_LEVELS and changed_settings(old_pyramid) == "levels=1:31,2:31:50,4:31"
    )
    assert (
        parse_settings(changed_settings(cfg)) == cfg and changed_settings(DetectorConfig()) == ""
    )  # health's string
    for bad, says in [
        ("nosuch=1", "'nosuch=1': expected KEY=VALUE"),
        ("split", "'split': expected KEY=VALUE"),
        ("levels=1", "'1' is not a pyramid"),  # a level is a factor and a window at least
        ("levels=1:31,2:30", "bad pyramid level (2, 30)"),  # DetectorConfig's own checks
        ("min_size=1.5", "'1.5' is not a int"),
        ("loose=maybe", "'maybe' is not a bool"),
        ("split_share=a,b", "'a,b' is not a tuple"),
        ("card_rescue_from=band,colour", "unknown card tests ['colour']"),  # DetectorConfig's own checks
        ("split=yes", "split: 'yes': '' (off) or any of grey, loose, edge"),
    ]:
        with pytest.raises(ValueError, match=re.escape(says)):
            parse_settings(bad)


@pytest.mark.parametrize("seed", range(6))
def test_the_distance_to_a_mark_is_exact_where_the_context_tests_look(seed: int) -> None:
    """`_distance` computes the distance transform only near the mark (a speed-up): wherever it is
    finite it must equal OpenCV's transform of the whole card region (but for float32 rounding: a
    unit or two in the last place, where equally short paths are summed in another order), and it may
    be infinite only beyond the reach of every context test."""
    from services.vision.detector import _distance, _reach

    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(60, 400, size=2))
    filled = np.zeros((h, w), np.uint8)
    bw, bh = int(rng.integers(8, max(9, w // 2))), int(rng.integers(8, max(9, h // 2)))
    x, y = int(rng.integers(0, w - bw + 1)), int(rng.integers(0, h - bh + 1))
    pts = np.stack([rng.integers(x, x + bw, 7), rng.integers(y, y + bh, 7)], axis=1).astype(np.int32)
    cv2.fillPoly(filled, [cv2.convexHull(pts)], 255)
    cv2.line(filled, (x, y), (x + bw - 1, y + bh - 1), 255, 2)  # not convex either
    ys, xs = np.nonzero(filled)
    box = (int(xs.min()), int(ys.min()), int(np.ptp(xs)) + 1, int(np.ptp(ys)) + 1)
    extent = float(np.sqrt(max(cv2.contourArea(cv2.convexHull(np.stack([xs, ys], 1))), 1.0)))
    reach = _reach(DetectorConfig(), extent)
    cut = _distance(filled, box, reach)
    whole = cv2.distanceTransform(cv2.bitwise_not(filled), cv2.DIST_L2, 3)
    finite = np.isfinite(cut)
    assert np.allclose(cut[finite], whole[finite], rtol=1e-6, atol=0)
    assert (whole[~finite] > reach).all()
    assert finite.sum() < filled.size or max(h, w) < 3 * reach  # it does leave something out


def _x_beside_a_letter(mark_ink: tuple[int, int, int], letter_ink: tuple[int, int, int]) -> np.ndarray:
    """An X and, just right of it on the same card, a K: "XK", a word if both are in one ink."""
    img = np.full((480, 640, 3), 110, np.uint8)
    cv2.rectangle(img, (120, 90), (520, 390), (235, 235, 235), -1)
    cv2.line(img, (260, 180), (380, 300), mark_ink, 18, cv2.LINE_AA)
    cv2.line(img, (380, 180), (260, 300), mark_ink, 18, cv2.LINE_AA)
    cv2.putText(img, "K", (395, 300), cv2.FONT_HERSHEY_SIMPLEX, 4.2, letter_ink, 14, cv2.LINE_AA)
    return img


@pytest.mark.parametrize("mark_ink", [(150, 150, 150), (170, 120, 60)], ids=["grey", "blue"])
def test_a_pale_mark_beside_a_black_letter_is_no_letter_of_its_word(
    detector: MarkDetector, mark_ink: tuple[int, int, int]
) -> None:
    """`letter_ink`: a letter of the same word is printed in the same ink; a black letter beside a pale
    X (another card's print, a stroke on the wall behind) does not make the X a letter."""
    img = _x_beside_a_letter(mark_ink, (20, 20, 20))
    config = dataclasses.replace(detector.config, letter_card=False, letter_other_ink=0.0)  # no "beside"
    assert MarkDetector(dataclasses.replace(config, letter_ink=0.0)).detect(img) == []
    found = MarkDetector(dataclasses.replace(config, letter_ink=0.25)).detect(img)
    assert [d.shape for d in found] == [Shape.X]


@pytest.mark.parametrize("ink", [(30, 30, 30), (150, 150, 150)], ids=["black", "grey"])
def test_an_x_in_a_word_of_its_own_ink_is_still_a_letter(
    detector: MarkDetector, ink: tuple[int, int, int]
) -> None:
    same_ink = MarkDetector(dataclasses.replace(detector.config, letter_ink=0.25))
    assert same_ink.detect(_x_beside_a_letter(ink, ink)) == []


# the card tests the rescue may overrule, without and with "beside" (the letter options' tests state their settings)
NO_BESIDE = tuple(r for r in DetectorConfig().card_rescue_from if r != "beside")
WITH_BESIDE = (*NO_BESIDE, "beside")


def _x_and_a_letter_on_two_cards(gap: int) -> np.ndarray:
    """An X on one card and a K of its ink on the next card, the two cards `gap` grey between them (235: one card)."""
    img = np.full((480, 640, 3), 110, np.uint8)
    cv2.rectangle(img, (120, 90), (560, 390), (235, 235, 235), -1)
    cv2.rectangle(img, (395, 90), (399, 390), (gap, gap, gap), -1)
    cv2.line(img, (260, 180), (380, 300), (30, 30, 30), 18, cv2.LINE_AA)
    cv2.line(img, (380, 180), (260, 300), (30, 30, 30), 18, cv2.LINE_AA)
    cv2.putText(img, "K", (405, 300), cv2.FONT_HERSHEY_SIMPLEX, 4.2, (30, 30, 30), 14, cv2.LINE_AA)
    return img


def test_a_letter_of_another_ink_or_card_is_beside_the_mark_and_may_be_overruled() -> None:
    """Round vision36b's options: with `letter_other_ink` or `letter_card`, a letter-test refusal where no shape
    beside the mark is in its ink, or on its card, is "beside", which the rescue may overrule when named in
    `card_rescue_from`; an X in a word of its own ink on its own card ("XK") stays a letter."""
    by_ink = DetectorConfig(letter_card=False, letter_other_ink=0.25, card_rescue_from=WITH_BESIDE)
    by_card = DetectorConfig(
        letter_card=True, letter_other_ink=0.0, letter_card_paper=0.0, card_rescue_from=WITH_BESIDE
    )
    both = dataclasses.replace(by_card, letter_other_ink=0.25)
    pale_beside_black = _x_beside_a_letter((150, 150, 150), (20, 20, 20))
    word = _x_beside_a_letter((30, 30, 30), (30, 30, 30))
    assert [d.shape for d in MarkDetector(by_ink).detect(pale_beside_black)] == [Shape.X]
    assert MarkDetector(by_card).detect(pale_beside_black) == []  # on its card: a letter, whatever its ink
    assert [d.shape for d in MarkDetector(both).detect(pale_beside_black)] == [Shape.X]
    for config in (by_ink, by_card, both):
        assert MarkDetector(config).detect(word) == []
    apart, together = _x_and_a_letter_on_two_cards(110), _x_and_a_letter_on_two_cards(235)
    assert [d.shape for d in MarkDetector(by_card).detect(apart)] == [Shape.X]
    assert MarkDetector(by_card).detect(together) == [] and MarkDetector(by_ink).detect(apart) == []
    # "beside" is overruled only where `card_rescue_from` names it; without the options there is no "beside"
    assert MarkDetector(dataclasses.replace(by_card, card_rescue_from=NO_BESIDE)).detect(apart) == []
    no_options = DetectorConfig(letter_card=False, letter_other_ink=0.0, card_rescue_from=WITH_BESIDE)
    assert MarkDetector(no_options).detect(apart) == []


def test_a_letter_on_a_page_of_another_grey_that_joins_the_card_is_beside_with_letter_card_paper() -> None:
    """Round vision36d: with `letter_card_paper`, the mark's card is only the light region of about its paper's grey,
    so a K on a lighter or darker page that joins the card at its edge is not on the card ("beside"); "XK" on one
    card stays a word."""
    plain = DetectorConfig(letter_card=True, letter_other_ink=0.0, letter_card_paper=0.0, card_rescue_from=WITH_BESIDE)
    paper = dataclasses.replace(plain, letter_card_paper=0.25)
    for card, page in ((235, 175), (200, 255)):  # a darker page; a lighter one
        img = _x_and_a_letter_on_two_cards(page)
        img[90:391, 120:395] = card
        cv2.line(img, (260, 180), (380, 300), (30, 30, 30), 18, cv2.LINE_AA)
        cv2.line(img, (380, 180), (260, 300), (30, 30, 30), 18, cv2.LINE_AA)
        img[90:391, 395:561] = page  # the K's side is a page of another grey, joined to the card
        cv2.putText(img, "K", (405, 300), cv2.FONT_HERSHEY_SIMPLEX, 4.2, (30, 30, 30), 14, cv2.LINE_AA)
        assert MarkDetector(plain).detect(img) == [], page  # one light region: the K is on the card
        assert [d.shape for d in MarkDetector(paper).detect(img)] == [Shape.X], page
    word = _x_beside_a_letter((30, 30, 30), (30, 30, 30))
    assert MarkDetector(paper).detect(word) == []
    assert MarkDetector(dataclasses.replace(paper, letter_other_ink=0.25)).detect(word) == []


def _o_and_a_letter_on_two_cards() -> np.ndarray:
    """An O on one card and a K of its ink on the next card, a dark gap between the cards."""
    img = _x_and_a_letter_on_two_cards(110)
    cv2.rectangle(img, (240, 160), (392, 320), (235, 235, 235), -1)
    cv2.circle(img, (320, 240), 60, (30, 30, 30), 18, cv2.LINE_AA)
    return img


def test_the_second_look_for_beside_is_only_where_the_rescue_could_keep_the_mark(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Round vision36c: the rescue never keeps an O, so for an O refused by the letter test the second look (is any
    shape beside it a letter of its word?) is not made; for an X it is, and only if `card_rescue_from` names
    "beside"."""
    calls: list[bool] = []
    real = detector_module._letter_beside

    def counted(*args: object, **kwargs: object) -> bool:
        calls.append(True)
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(detector_module, "_letter_beside", counted)
    both = DetectorConfig(
        letter_card=True, letter_other_ink=0.25, letter_card_paper=0.0, card_rescue_from=WITH_BESIDE
    )
    cases = [
        (both, _x_and_a_letter_on_two_cards(110), [Shape.X], True),
        (both, _o_and_a_letter_on_two_cards(), [], False),
        (dataclasses.replace(both, card_rescue_from=NO_BESIDE), _x_and_a_letter_on_two_cards(110), [], False),
    ]
    for config, img, shapes, second_look in cases:
        MarkDetector(dataclasses.replace(config, letter_card=False, letter_other_ink=0.0)).detect(img)
        first_looks = len(calls)  # the letter test's looks without the options
        calls.clear()
        assert [d.shape for d in MarkDetector(config).detect(img)] == shapes
        assert first_looks > 0 and (len(calls) > first_looks) == second_look
        calls.clear()


def _poster(word: str, size: int) -> np.ndarray:
    """A word printed big on a light poster in Pillow's bundled typeface (not the held-out generator's
    DejaVu, not OpenCV's stroke fonts): its O and X are thick rings and crosses, as on a real sign."""
    img = Image.new("RGB", (640, 480), (90, 110, 100))
    draw = ImageDraw.Draw(img)
    draw.rectangle((20, 140, 620, 360), fill=(225, 225, 220))
    draw.text((40, 160), word, font=ImageFont.load_default(size=size), fill=(20, 30, 25))
    return cv2.GaussianBlur(np.asarray(img)[:, :, ::-1], (3, 3), 0)


POSTERS = [(w, s) for w in ("OPEN", "TOXIC", "NO", "OK", "BOX", "ZOO", "XO") for s in (110, 140, 170)]


def test_a_big_o_or_x_in_a_printed_word_is_no_mark_at_every_level(detector: MarkDetector) -> None:
    """Round vision13: letters this big are components only at the quarter level, where the text-line
    test runs too (`text_max_f` 4); without it (2, before), most of these words give a false O or X."""
    before = MarkDetector(dataclasses.replace(detector.config, text_max_f=2, text_paper=0.0))
    assert sum(bool(before.detect(_poster(w, s))) for w, s in POSTERS) >= len(POSTERS) // 2
    assert [(w, s) for w, s in POSTERS if detector.detect(_poster(w, s))] == []


def _turned(img: np.ndarray, degrees: float) -> np.ndarray:
    h, w = img.shape[:2]
    turn = cv2.getRotationMatrix2D((w / 2, h / 2), degrees, 1.0)
    return cv2.warpAffine(img, turn, (w, h), borderMode=cv2.BORDER_REPLICATE)


def test_a_printed_word_seen_turned_is_no_mark(detector: MarkDetector) -> None:
    """Round vision20: a word turned by a camera's roll or hung askew is still a line of letters
    (`text_turned`); the horizontal test alone took most of these for marks from 10 degrees on. Words
    of two letters (NO, OK, XO) are caught only turned a little (round vision20b: one neighbour is a line
    only when it is the candidate's twin), and a big word at 45 degrees can still pass (its letters'
    upright boxes are far from its letters)."""
    flat = MarkDetector(dataclasses.replace(detector.config, text_turned=False))
    long_words = [(w, s) for w, s in POSTERS if len(w) >= 3]
    cases = [(w, s, a) for w, s in long_words for a in (-20, 15, 30, 45)]
    before = [c for c in cases if flat.detect(_turned(_poster(c[0], c[1]), c[2]))]
    after = [c for c in cases if detector.detect(_turned(_poster(c[0], c[1]), c[2]))]
    assert len(before) >= len(cases) // 2, before  # 30 of 48 with the committed models
    assert len(after) <= 2, after  # one of 48 with the committed models: OPEN at 140 px, 45 degrees
    short = [(w, s, a) for w, s in POSTERS if len(w) == 2 for a in (-10, 5, 10)]
    assert sum(bool(flat.detect(_turned(_poster(w, s), a))) for w, s, a in short) >= len(short) // 2
    assert [c for c in short if detector.detect(_turned(_poster(c[0], c[1]), c[2]))] == []


def _row(neighbours_on_paper: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A grey image and its components: a dark letter-sized blob at 100..160 with two like it to its
    right on one baseline, either printed on the paper (light all round) or standing in a dark band
    (like the background beyond a card's edge)."""
    g = np.full((200, 400), 220, np.uint8)
    if not neighbours_on_paper:
        cv2.rectangle(g, (162, 60), (399, 180), 60, -1)
    for x in (100, 170, 240):
        cv2.rectangle(g, (x, 80), (x + 55, 150), 30, -1)
        cv2.rectangle(g, (x + 15, 95), (x + 40, 135), 220 if x == 100 or neighbours_on_paper else 60, -1)
    binary = cv2.inRange(g, 0, 45)
    _, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=8)
    return g, labels, stats


def test_a_letter_of_a_text_line_is_printed_on_paper() -> None:
    """`text_paper`: the neighbours that make a candidate a letter in a line of text must have paper
    round them; dark shapes in a dark band beside a card are not the next letters of a word."""
    for on_paper in (True, False):
        g, labels, stats = _row(on_paper)
        i = int(labels[85, 102])
        assert _in_text_line(stats, i, g, labels, 0.0)  # without the test, both rows are words
        assert _in_text_line(stats, i, g, labels, 0.7) is on_paper


def test_held_out_lens_distorts_frames_and_labels_as_opencvs_model_says() -> None:
    """`HeldOutGenerator(lens=K)`: the same scenes as without it (it draws no random numbers), seen through a
    barrel lens in OpenCV's radial model; each mark's label is its ink's extent in the distorted frame."""
    import cv2

    from services.vision.heldout import HeldOutGenerator, lens_camera, lens_maps

    w, h = 640, 480
    with pytest.raises(ValueError, match="between 0 and 0.379"):  # k1 = -0.6 folds the corners back
        lens_maps(0.6, w, h)
    mx, my = lens_maps(0.3, w, h)
    assert abs(mx[h // 2, w // 2] - w / 2) < 0.5 and abs(my[h // 2, w // 2] - h / 2) < 0.5  # the centre stays
    assert mx[0, 0] < 0 and my[0, 0] < 0  # a barrel lens shows more than the pinhole frame at its corners
    # the maps invert OpenCV's own forward model: projecting a map's source lands on that pixel
    k, dist = lens_camera(0.3, w, h)
    for v, u in ((10, 10), (100, 600), (240, 320), (470, 5)):
        src = np.array([[[mx[v, u], my[v, u]]]], np.float64)
        normalised = (src - k[:2, 2]) / k[0, 0]
        back, _ = cv2.projectPoints(np.dstack([normalised, np.ones((1, 1))]).reshape(1, 3), np.zeros(3), np.zeros(3),
                                    k, dist)
        assert np.allclose(back.reshape(2), (u, v), atol=0.5)
    pinhole, lensed = HeldOutGenerator(seed=11), HeldOutGenerator(seed=11, lens=0.3)
    assert np.array_equal(HeldOutGenerator(seed=12, lens=0.0).frame(Shape.X)[0], HeldOutGenerator(seed=12).frame(Shape.X)[0])
    centre = np.array([w / 2, h / 2])
    for i in range(9):
        shape = SHAPES[i % 3]
        (a, la), (b, lb) = pinhole.frame(shape), lensed.frame(shape)
        assert la is not None and lb is not None and la.shape is lb.shape is shape
        assert not np.array_equal(a, b)
        ca = np.array([la.box[0] + la.box[2] / 2, la.box[1] + la.box[3] / 2])
        cb = np.array([lb.box[0] + lb.box[2] / 2, lb.box[1] + lb.box[3] / 2])
        assert np.linalg.norm(cb - centre) <= np.linalg.norm(ca - centre) + 2  # barrel: pulled towards the centre
        x, y, bw, bh = lb.box
        assert 0 <= x and 0 <= y and x + bw <= w and y + bh <= h


def _solid_triangle(bow: float) -> detector_module._Blob:
    """A 40 px filled triangle whose sides bow inwards by `bow` of its size at their middles (as the adaptive
    threshold eats a filled shape's edges), as the shape tests see it."""
    corners = np.array([(30.0, 10.0), (70.0, 10.0), (50.0, 45.0)])
    centre = corners.mean(axis=0)
    outline = []
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        for t in np.linspace(0, 1, 20, endpoint=False):
            p = a + t * (b - a)
            outline.append(p + (centre - p) / np.linalg.norm(centre - p) * bow * 40 * np.sin(np.pi * t))
    mask = np.zeros((60, 100), np.uint8)
    cv2.fillPoly(mask, [np.round(np.array(outline)).astype(np.int32)], 255)
    blob = detector_module._blob(cv2.copyMakeBorder(mask, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0), 40.0)
    assert blob is not None
    return blob


def test_the_filled_triangle_bars_are_settings() -> None:
    """`filled_solidity` and `filled_fill` (round vision41): a straight-sided filled triangle is claimed at the
    defaults with a high confidence; one bowed by the local threshold is not, and is at lower bars, at 0.5 on the
    fill bar's edge."""
    config = DetectorConfig()
    straight = detector_module._classify(_solid_triangle(0.0), config)
    assert straight is not None and straight[0] is Shape.TRIANGLE and straight[1] > 0.75
    bowed = _solid_triangle(0.04)  # fills 0.85 of its hull, as a 30-50 px one on the tuning frames
    assert detector_module._classify(bowed, config) is None
    lower = dataclasses.replace(config, filled_solidity=0.8, filled_fill=0.7)
    judged = detector_module._classify(bowed, lower)
    assert judged is not None and judged[0] is Shape.TRIANGLE and 0.5 <= judged[1] < straight[1]
    assert detector_module._classify(_solid_triangle(0.0), dataclasses.replace(config, filled_fill=0.999)) is None


def _cross_blob(bar: float, angle: float = 90.0) -> detector_module._Blob:
    """An X of two 80 px bars `bar` of their length wide crossing at `angle` degrees, as the shape tests see it."""
    mask = np.zeros((120, 120), np.uint8)
    for a in (90 - angle / 2, 90 + angle / 2):
        dx, dy = 40 * np.cos(np.radians(a)), 40 * np.sin(np.radians(a))
        cv2.line(mask, (round(60 - dx), round(60 - dy)), (round(60 + dx), round(60 + dy)), 255, round(bar * 80))
    blob = detector_module._blob(mask, 80.0)
    assert blob is not None
    return blob


def test_a_thick_x_is_claimed_under_the_solidity_limit() -> None:
    """`x_solidity` (round vision65b's default 0.6): an X of bars a tenth of their length wide fills about a third of
    its hull and is claimed; one of bars 0.22 of their length wide (tape strips, a broad marker) fills 0.55 of it and
    is claimed too (also crossing at 60 degrees), while at the old limit, 0.5, it was left to the verifier. A blot of
    bars 0.45 wide is never an X."""
    config = DetectorConfig()
    thin = detector_module._classify(_cross_blob(0.1), config)
    assert thin is not None and thin[0] is Shape.X
    thick = _cross_blob(0.22)
    judged = detector_module._classify(thick, config)
    assert judged is not None and judged[0] is Shape.X and judged[1] >= 0.5
    assert detector_module._classify(_cross_blob(0.22, angle=60.0), config) is not None
    old = dataclasses.replace(config, x_solidity=detector_module.X_SOLIDITY)
    assert detector_module._classify(thick, old) is None
    assert detector_module._classify(_cross_blob(0.1), old) is not None
    assert detector_module._classify(_cross_blob(0.45), config) is None  # a blot, not four arms
