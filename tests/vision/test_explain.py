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
from services.vision.explain import FILLED_TRIANGLE, REASONS, near_misses


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
    misses = near_misses(detector, img)
    assert [(m.shape, m.stage) for m in misses] == [(Shape.TRIANGLE, "verifier")]
    assert box_overlap(misses[0].box, box) >= 0.8
    assert misses[0].reason == REASONS["verifier"] + FILLED_TRIANGLE


def test_a_reported_mark_or_an_empty_frame_has_nothing_to_explain(detector: MarkDetector) -> None:
    img, _ = _card(0.3)
    assert [d.shape for d in detector.detect(img)] == [Shape.TRIANGLE]
    assert near_misses(detector, img) == []
    x, _ = _card(0.3, shape=Shape.X, filled=False)
    assert near_misses(detector, x) == []
    assert near_misses(detector, np.full((480, 640, 3), 128, np.uint8)) == []


def test_a_large_frame_is_explained_in_its_own_pixels(detector: MarkDetector) -> None:
    img, box = _card(3.0)
    big = cv2.resize(img, (1280, 960), interpolation=cv2.INTER_LINEAR)
    (miss,) = near_misses(detector, big)
    assert box_overlap(miss.box, tuple(2 * v for v in box)) >= 0.8  # type: ignore[arg-type]
    assert max(miss.box[2:]) > 140  # not the 640-px frame's box


def test_the_other_rules_read_as_words() -> None:
    assert "clear margin" in REASONS["O margin"] and "line of text" in REASONS["text line"]
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
