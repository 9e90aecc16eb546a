"""`detect --explain` (`services/vision/explain.py`): a shape the tests read as a mark but the detector did not report
is named with the rule that refused it; a reported mark, or a frame with nothing mark-like, gives no such line."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from bench.vision_cards import card_frame
from schemas.messages import Shape
from services.vision.__main__ import app
from services.vision.detector import DetectorConfig, MarkDetector, box_overlap
from services.vision.explain import FILLED_TRIANGLE, REASONS, CardCheck, NearMiss, explained


@pytest.fixture(scope="module")
def detector() -> MarkDetector:
    return MarkDetector(DetectorConfig())


def _card(
    border: float, background: str = "grey", shape: Shape = Shape.TRIANGLE, filled: bool = True
) -> tuple[np.ndarray, tuple[int, int, int, int]]:
    return card_frame(background, shape, filled, 80, border, 25.0, np.random.default_rng(5))


@pytest.mark.parametrize(("border", "background"), [(3.0, "grey"), (0.3, "white")])
def test_a_filled_triangle_taken_for_a_painted_one_is_explained(
    detector: MarkDetector, border: float, background: str
) -> None:
    img, box = _card(border, background)
    assert detector.detect(img) == []
    misses = explained(detector, img)[1]
    assert [(m.shape, m.stage) for m in misses] == [(Shape.TRIANGLE, "verifier")]
    assert box_overlap(misses[0].box, box) >= 0.8
    assert misses[0].reason == REASONS["verifier"] + FILLED_TRIANGLE


def test_a_reported_mark_or_an_empty_frame_has_nothing_to_explain(detector: MarkDetector) -> None:
    img, _ = _card(0.3)
    assert [d.shape for d in detector.detect(img)] == [Shape.TRIANGLE]
    assert explained(detector, img)[1] == []
    x, _ = _card(0.3, shape=Shape.X, filled=False)
    assert explained(detector, x)[1] == []
    assert explained(detector, np.full((480, 640, 3), 128, np.uint8))[1] == []


def test_a_large_frame_is_explained_in_its_own_pixels(detector: MarkDetector) -> None:
    img, box = _card(3.0)
    big = cv2.resize(img, (1280, 960), interpolation=cv2.INTER_LINEAR)
    (miss,) = explained(detector, big)[1]
    assert box_overlap(miss.box, tuple(2 * v for v in box)) >= 0.8  # type: ignore[arg-type]
    assert max(miss.box[2:]) > 140  # not the 640-px frame's box


def test_the_other_rules_read_as_words() -> None:
    assert "clear margin" in REASONS["O margin"] and "line of text" in REASONS["text line"]
    assert "reflection" in REASONS["unnamed"]  # a lamp's reflection on a glossy card (stop 113)
    from services.vision.detector import STAGES

    assert all(stage in STAGES for stage in REASONS)  # a renamed stage cannot go unexplained silently


def test_detect_explain_writes_reasons_on_stderr_only(tmp_path: Path) -> None:
    wide, _ = _card(3.0)
    ok, _ = _card(0.3)
    cv2.imwrite(str(tmp_path / "wide.png"), wide)
    cv2.imwrite(str(tmp_path / "ok.png"), ok)
    runner = CliRunner()
    args = ["detect", str(tmp_path / "wide.png"), str(tmp_path / "ok.png")]
    plain = runner.invoke(app, args)
    explained = runner.invoke(app, [*args, "--explain"])
    assert plain.exit_code == explained.exit_code == 0
    assert plain.stderr == ""
    observed = [json.loads(line)["marks"] for line in explained.stdout.splitlines()]  # one JSON line per image
    assert observed == [json.loads(line)["marks"] for line in plain.stdout.splitlines()]
    assert observed[0] == [] and [m["shape"] for m in observed[1]] == ["TRIANGLE"]
    lines = explained.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{tmp_path / 'wide.png'}: TRIANGLE at ")
    assert "not reported: the learned verifier" in lines[0] and "trim the card" in lines[0]


def test_card_check_counts_each_shape_and_rule_once_a_frame() -> None:
    seen = CardCheck()
    assert seen.summary() == ["no frame was read"]
    miss = NearMiss(Shape.TRIANGLE, (1, 2, 3, 4), "verifier")
    seen.add([Shape.X, Shape.X], [miss, NearMiss(Shape.TRIANGLE, (9, 9, 3, 4), "verifier")])
    seen.add([], [miss, NearMiss(Shape.O, (5, 5, 5, 5), "O margin")])
    seen.add([], [])
    assert seen.reported == {Shape.X: 1} and seen.refused == {(Shape.TRIANGLE, "verifier"): 2, (Shape.O, "O margin"): 1}
    lines = seen.summary()
    assert lines[:2] == ["3 frame(s) looked at", "X: reported in 1 of 3 frames"]
    assert lines[2] == f"TRIANGLE: read but not reported in 2 of 3 frames: {miss.reason}"  # the most frequent first
    assert lines[3].startswith("O: read but not reported in 1 of 3 frames: an O needs a clear margin")
    empty = CardCheck()
    empty.add([], [])
    assert "nothing mark-like was seen" in empty.summary()[-1] and "reflection" in empty.summary()[-1]  # stop 113


def test_check_looks_at_a_folder_of_frames(tmp_path: Path) -> None:
    for name, border in (("a_wide", 3.0), ("b_ok", 0.3), ("c_wide", 3.0)):
        cv2.imwrite(str(tmp_path / f"{name}.png"), _card(border)[0])
    result = CliRunner().invoke(app, ["check", "--source", str(tmp_path), "--frames", "10"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[:2] == ["3 frame(s) looked at", "TRIANGLE: reported in 1 of 3 frames"]
    assert lines[2].startswith("TRIANGLE: read but not reported in 2 of 3 frames: the learned verifier")
    two = CliRunner().invoke(app, ["check", "--source", str(tmp_path), "--frames", "2"])
    assert two.stdout.splitlines()[0] == "2 frame(s) looked at"


def test_check_without_its_camera_names_it_and_the_alternatives() -> None:
    result = CliRunner().invoke(app, ["check", "--source", "camera:/dev/hri-no-such-camera", "--frames", "2"])
    assert result.exit_code == 1
    assert "camera:/dev/hri-no-such-camera" in result.stderr and "synthetic" in result.stderr
    assert result.stdout.splitlines() == ["no frame was read"]
    bad = CliRunner().invoke(app, ["check", "--source", "bogus:thing"])
    assert bad.exit_code == 2 and "bogus" in bad.stderr


def test_explained_reports_what_detect_reports(detector: MarkDetector) -> None:
    for border, size in ((0.3, (640, 480)), (0.3, (1280, 960)), (3.0, (1280, 960))):
        img = cv2.resize(_card(border)[0], size, interpolation=cv2.INTER_LINEAR)
        assert explained(detector, img)[0] == detector.detect(img), (border, size)
