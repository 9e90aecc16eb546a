"""The look ahead (`lookahead.py`, round vision26): the detector in steps gives exactly `detect`'s detections,
even with another frame's steps run in between on its twin; a newer frame with a danger mark is published
at once and the older one dropped; one without waits ahead, its coarser levels done, and is finished next;
a still newer frame replaces it; files never look ahead."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector, Step, finish, to_gray
from services.vision.lookahead import LookAhead
from services.vision.sources import Frame, ImageFolderSource, SyntheticSource
from services.vision.synthetic import MILD, SceneGenerator


@pytest.fixture(scope="module")
def detector() -> MarkDetector:
    return MarkDetector()


@pytest.fixture(scope="module")
def scenes() -> dict[str, np.ndarray]:
    """Cluttered frames: one with nothing held up, one with each mark."""
    gen = SceneGenerator(seed=26, variation=MILD.only(distractors=(4, 6)))
    out = {"none": gen.render(gen.scene(None))[0]}
    for shape in Shape:
        out[shape.value] = gen.render(gen.scene(shape))[0]
    return out


def _key(found: list) -> list[tuple[str, tuple[int, ...], float]]:  # type: ignore[type-arg]
    return [(d.shape.value, tuple(d.box), round(d.confidence, 6)) for d in found]


def test_two_frames_stepped_in_turn_on_twins_get_detect_s_detections(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    expected = {name: _key(detector.detect(img)) for name, img in scenes.items()}
    twin = detector.twin()
    assert twin.verifier is detector.verifier and twin.proposer is detector.proposer  # the networks are shared
    names = list(scenes)
    for a, b in zip(names, names[1:] + names[:1], strict=True):
        results: dict[str, list] = {}  # type: ignore[type-arg]
        # out of step: three of a's steps to each of b's, so the two are at different pyramid levels and
        # components at once; their working state (level, grey images, vetoes) must not mix
        pending = [(a, detector.steps(scenes[a]), 3), (b, twin.steps(scenes[b]), 1)]
        while pending:
            for entry in list(pending):
                name, steps, pace = entry
                for _ in range(pace):
                    try:
                        next(steps)
                    except StopIteration as done:
                        results[name] = _key(done.value)
                        pending.remove(entry)
                        break
        assert results[a] == expected[a] and results[b] == expected[b], (a, b)


def test_a_twin_keeps_its_own_frame_state(detector: MarkDetector, scenes: dict[str, np.ndarray]) -> None:
    twin = detector.twin()
    paused = detector.steps(scenes["O"])
    while next(paused) is not Step.FINE:  # its coarser levels judged, the finest to come
        pass
    finish(twin.steps(scenes["none"]))  # another frame, start to end, on the twin
    gray = to_gray(scenes["O"])
    coarse = max(f for f, *_ in detector.config.levels)
    size = (gray.shape[1] // coarse, gray.shape[0] // coarse)
    assert np.array_equal(detector._greys[coarse], cv2.resize(gray, size, interpolation=cv2.INTER_AREA))
    assert _key(finish(paused)) == _key(detector.detect(scenes["O"]))


def test_fine_comes_once_after_the_coarser_levels_and_never_on_a_danger_frame(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    x_steps = list(_all_steps(detector, scenes["X"]))
    assert _key(finish(detector.steps(scenes["X"]))) and Step.FINE not in x_steps  # confirmed on a coarser level
    o_steps = list(_all_steps(detector, scenes["O"]))
    assert o_steps.count(Step.FINE) == 1
    assert len(o_steps) > o_steps.index(Step.FINE) + 10  # the finest level's components, the proposer still to come
    every = MarkDetector(DetectorConfig(danger_first=False), verifier=detector.verifier)
    assert Step.FINE not in list(_all_steps(every, scenes["O"]))  # no coarser-first order, no pause


def _all_steps(detector: MarkDetector, image: np.ndarray) -> list[Step]:
    return list(detector.steps(image))


def _frame(image: np.ndarray, index: int) -> Frame:
    return Frame(image, time.time(), index)


def _newer_at(calls: dict[int, Frame]) -> tuple[Callable[[], Frame | None], list[int]]:
    """A live source's newer-frame callback that has `calls[n]` ready at its n-th call (1-based)."""
    seen = [0]

    def newer() -> Frame | None:
        seen[0] += 1
        return calls.get(seen[0])

    return newer, seen


def test_a_newer_frame_with_an_x_is_published_at_once_and_the_older_dropped(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    frames = LookAhead(detector)
    newer, seen = _newer_at({3: _frame(scenes["X"], 2)})
    out = frames.finish(frames.start(_frame(scenes["none"], 1)), newer)
    assert out.frame.index == 2 and [d.shape for d in out.found or []] == [Shape.X]
    assert seen[0] == 3  # the older frame's steps stopped at the look that found the X
    assert frames.ahead is None and frames.counts.dangers == 1 and frames.counts.looks == 1
    # both detectors are free again: two more frames can be in flight
    again = frames.finish(frames.start(_frame(scenes["O"], 3)), _newer_at({1: _frame(scenes["none"], 4)})[0])
    assert _key(again.found or []) == _key(detector.detect(scenes["O"]))
    waiting = frames.take_ahead()
    assert waiting is not None and waiting.frame.index == 4


def test_a_newer_frame_without_danger_waits_ahead_and_is_finished_as_detect_would(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    frames = LookAhead(detector)
    newer, _ = _newer_at({2: _frame(scenes["O"], 2), 5: _frame(scenes["O"].copy(), 3)})
    first = frames.finish(frames.start(_frame(scenes["none"], 1)), newer)
    assert first.frame.index == 1 and _key(first.found or []) == _key(detector.detect(scenes["none"]))
    assert frames.counts.looks == 2 and frames.counts.replaced == 1  # frame 3 came and replaced frame 2
    waiting = frames.take_ahead()
    assert waiting is not None and waiting.frame.index == 3 and waiting.found is None  # its finest level to come
    done = frames.finish(waiting, lambda: None)
    assert _key(done.found or []) == _key(detector.detect(scenes["O"]))
    assert frames.take_ahead() is None


def test_without_danger_first_or_when_off_it_never_looks(detector: MarkDetector, scenes: dict[str, np.ndarray]) -> None:
    every = MarkDetector(DetectorConfig(danger_first=False), verifier=detector.verifier)
    for frames in (LookAhead(every), LookAhead(detector, enabled=False)):
        newer, seen = _newer_at({1: _frame(scenes["X"], 2)})
        out = frames.finish(frames.start(_frame(scenes["none"], 1)), newer)
        assert out.frame.index == 1 and seen[0] == 0 and not frames.enabled


def test_a_frame_the_detector_refuses_while_looking_ahead_is_counted_and_dropped(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    skipped: list[tuple[int, str]] = []
    frames = LookAhead(detector, on_skip=lambda f, error: skipped.append((f.index, error)))
    bad = np.zeros((4, 4, 3), np.uint8)[:, :, :2]  # two channels: not an image the detector reads
    newer, _ = _newer_at({1: _frame(bad, 2)})
    out = frames.finish(frames.start(_frame(scenes["O"], 1)), newer)
    assert out.frame.index == 1 and _key(out.found or []) == _key(detector.detect(scenes["O"]))
    assert frames.counts.skipped == 1 and skipped and skipped[0][0] == 2 and frames.ahead is None


def test_live_sources_offer_newer_frames_and_files_never(tmp_path: Path) -> None:
    cv2.imwrite(str(tmp_path / "a.png"), np.full((48, 64, 3), 200, np.uint8))
    folder = ImageFolderSource(str(tmp_path), [tmp_path / "a.png"])
    folder.open()
    assert folder.fresh() is False
    synthetic = SyntheticSource("synthetic:none", width=160, height=120)
    assert synthetic.fresh() is True  # rendered when read: the fps cap paces it


def test_an_error_while_looking_ahead_frees_the_frame_s_detector(
    detector: MarkDetector, scenes: dict[str, np.ndarray]
) -> None:
    frames = LookAhead(detector)

    def broken() -> Frame | None:
        raise RuntimeError("the camera went away")

    with pytest.raises(RuntimeError):
        frames.finish(frames.start(_frame(scenes["none"], 1)), broken)
    # nothing is left in flight: two frames can be started again, and finished as detect would
    one, two = frames.start(_frame(scenes["O"], 2)), frames.start(_frame(scenes["X"], 3))
    assert _key(frames.finish(one, lambda: None).found or []) == _key(detector.detect(scenes["O"]))
    assert _key(frames.finish(two, lambda: None).found or []) == _key(detector.detect(scenes["X"]))
