"""Frame sources: spec parsing, bad paths, files, folders, schedules, the synthetic scene."""

from __future__ import annotations

import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from schemas.messages import Shape
from services.vision.detector import MarkDetector
from services.vision.sources import (
    ALTERNATIVES,
    CameraSource,
    EndOfStream,
    ImageFolderSource,
    SourceError,
    SyntheticSource,
    VideoFileSource,
    open_source,
    parse_schedule,
)


def _write_video(path: Path, frames: int, size: tuple[int, int] = (160, 120)) -> None:
    w = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 20, size)
    assert w.isOpened()
    for i in range(frames):
        w.write(np.full((size[1], size[0], 3), 10 * i % 255, np.uint8))
    w.release()


@pytest.mark.parametrize("spec", ["/no/such/file.mp4", "", "   "])
def test_bad_specs_name_the_source_and_the_alternatives(spec: str) -> None:
    with pytest.raises(SourceError) as err:
        open_source(spec)
    assert ALTERNATIVES in str(err.value)
    if spec.strip():
        assert spec in str(err.value)


def test_missing_camera_is_a_clear_error() -> None:
    for spec in ("camera:/dev/video97", "camera:97"):
        src = open_source(spec)
        assert isinstance(src, CameraSource)
        with pytest.raises(SourceError) as err:
            src.open()
        assert "video97" in str(err.value) or "camera:97" in str(err.value)
        assert "synthetic:paper" in str(err.value)
        src.close()


def test_video_file_delivers_every_frame_then_ends(tmp_path: Path) -> None:
    _write_video(tmp_path / "clip.avi", 7)
    src = open_source(str(tmp_path / "clip.avi"))
    assert isinstance(src, VideoFileSource)
    src.open()
    assert src.default_fps == pytest.approx(20.0)
    frames = [src.read(1.0) for _ in range(7)]
    assert [f.index for f in frames if f] == list(range(1, 8))
    assert all(f is not None and f.image.shape == (120, 160, 3) for f in frames)
    assert all(abs(f.stamp - time.time()) < 5 for f in frames if f)
    with pytest.raises(EndOfStream):
        src.read(1.0)
    src.close()


def test_video_file_loops_when_asked(tmp_path: Path) -> None:
    _write_video(tmp_path / "clip.avi", 3)
    src = open_source(str(tmp_path / "clip.avi"), loop=True)
    src.open()
    assert all(src.read(1.0) is not None for _ in range(8))
    src.close()


def test_undecodable_video_is_a_source_error(tmp_path: Path) -> None:
    bad = tmp_path / "broken.mp4"
    bad.write_bytes(b"this is not a video")
    src = open_source(str(bad))
    with pytest.raises(SourceError, match="cannot decode"):
        src.open()


def test_folder_and_glob_in_name_order_skipping_unreadable(tmp_path: Path) -> None:
    for i in (2, 0, 1):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), np.full((20, 30, 3), i * 50, np.uint8))
    (tmp_path / "f15.png").write_bytes(b"garbage")  # sorted between f1 and f2
    (tmp_path / "notes.txt").write_text("ignored")
    for spec in (str(tmp_path), str(tmp_path / "f*.png")):
        src = open_source(spec)
        assert isinstance(src, ImageFolderSource)
        src.open()
        levels = [int(src.read(1.0).image[0, 0, 0]) for _ in range(3)]  # type: ignore[union-attr]
        assert levels == [0, 50, 100]
        with pytest.raises(EndOfStream):
            src.read(1.0)


def test_empty_folder_is_a_source_error(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="no images"):
        open_source(str(tmp_path)).open()


def test_schedule_file_format() -> None:
    steps = parse_schedule("# demo\n2 X\n1.5 none  # pause\n3 triangle\n")
    assert steps == [(2.0, Shape.X), (1.5, None), (3.0, Shape.TRIANGLE)]
    for bad in ("2 square", "x X", "-1 O", "3", ""):
        with pytest.raises(SourceError):
            parse_schedule(bad)


def test_unknown_scenario_is_a_source_error() -> None:
    with pytest.raises(SourceError, match="neither a built-in"):
        open_source("synthetic:nosuchscenario").open()


def _synthetic(tmp_path: Path, schedule: str) -> SyntheticSource:
    """An open synthetic source following `schedule`."""
    sched = tmp_path / "s.txt"
    sched.write_text(schedule)
    src = open_source(f"synthetic:{sched}")
    assert isinstance(src, SyntheticSource)
    src.open()
    return src


def test_synthetic_source_follows_schedule_and_commands(tmp_path: Path) -> None:
    src = _synthetic(tmp_path, "100 O\n")
    det = MarkDetector()
    frame = src.read(1.0)
    assert frame is not None and frame.image.shape == (480, 640, 3)
    assert [d.shape for d in det.detect(frame.image)] == [Shape.O]
    src.set_shape(Shape.X)
    assert [d.shape for d in det.detect(src.read(1.0).image)] == [Shape.X]  # type: ignore[union-attr]
    src.set_shape(None)
    assert det.detect(src.read(1.0).image) == []  # type: ignore[union-attr]


def test_builtin_cycle_scenario_changes_shape_over_time() -> None:
    src = open_source("synthetic:cycle")
    assert isinstance(src, SyntheticSource)
    src.open()
    assert src.current_shape() is Shape.X
    src._t0 -= 3.5  # jump 3.5 s ahead instead of sleeping
    assert src.current_shape() is Shape.O
    src._t0 -= 6.0
    assert src.current_shape() is None


def test_synthetic_frames_carry_sensor_noise_that_changes_between_frames(tmp_path: Path) -> None:
    src = _synthetic(tmp_path, "100 none\n")
    before = time.time()
    frames = [src.read(1.0) for _ in range(12)]
    images = [f.image for f in frames if f is not None]
    assert len(images) == 12 and all(before <= f.stamp <= time.time() for f in frames if f is not None)
    still = src._stills[None].astype(np.int16)
    for image in images:  # noise of about NOISE_SIGMA grey levels on every frame, never the bare still
        assert 2.0 < float(np.std(image.astype(np.int16) - still)) < 4.0
    assert len({img.tobytes() for img in images}) > 1  # not one pattern for every frame
