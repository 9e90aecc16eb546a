"""The lens calibration (`--calibration`): OpenCV FileStorage files read, bad ones named, and frames
undistorted so that a mark bent by the lens is straight again."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from services.vision.calibration import Calibration, Undistorter
from services.vision.detector import MarkDetector
from tests.conftest import ROOT

K = np.array([[420.0, 0.0, 320.0], [0.0, 420.0, 240.0], [0.0, 0.0, 1.0]])
D = np.array([[-0.32, 0.09, 0.0, 0.0, 0.0]])  # strong barrel distortion


def _write(path: Path, **nodes: object) -> Path:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in nodes.items():
        fs.write(key, value)
    fs.release()
    return path


def _through_the_lens(scene: np.ndarray) -> np.ndarray:
    """What a camera with K and D shows of `scene` (what a distortion-free camera with K sees)."""
    h, w = scene.shape[:2]
    grid = np.stack(np.meshgrid(np.arange(w), np.arange(h)), axis=-1).reshape(-1, 1, 2).astype(np.float64)
    ideal = cv2.undistortPoints(grid, K, D, P=K).reshape(h, w, 2).astype(np.float32)
    return cv2.remap(scene, ideal[..., 0], ideal[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def _x_card_near_the_corner() -> np.ndarray:
    img = np.full((480, 640, 3), 120, np.uint8)
    cv2.rectangle(img, (400, 20), (620, 230), (235, 235, 235), -1)
    cv2.line(img, (440, 50), (580, 200), (30, 30, 30), 18, cv2.LINE_AA)
    cv2.line(img, (580, 50), (440, 200), (30, 30, 30), 18, cv2.LINE_AA)
    return img


def test_a_calibration_file_is_read_in_yaml_and_json(tmp_path: Path) -> None:
    for name in ("cam.yaml", "cam.json"):
        path = _write(
            tmp_path / name, camera_matrix=K, distortion_coefficients=D, image_width=640, image_height=480
        )
        cal = Calibration.load(path)
        assert np.allclose(cal.camera_matrix, K) and np.allclose(cal.distortion, D) and cal.size == (640, 480)
    # ROS's other name for the coefficients, no size: the matrix is used as it is for any frame
    cal = Calibration.load(_write(tmp_path / "ros.yaml", camera_matrix=K, dist_coeffs=D[:, :4]))
    assert cal.size is None and np.allclose(cal.matrix_for(1280, 960), K)
    # made at 640x480, used at 320x240: the focal lengths and centre scale with the frame
    half = Calibration.load(tmp_path / "cam.yaml").matrix_for(320, 240)
    assert np.allclose(half, [[210, 0, 160], [0, 210, 120], [0, 0, 1]])


@pytest.mark.parametrize(
    ("nodes", "says"),
    [
        ({}, "no such file"),
        ({"distortion_coefficients": D}, "needs camera_matrix"),
        ({"camera_matrix": K}, "needs distortion_coefficients"),
        ({"camera_matrix": K, "distortion_coefficients": np.zeros((1, 3))}, "4, 5, 8, 12 or 14 numbers"),
        ({"camera_matrix": -K, "distortion_coefficients": D}, "focal lengths"),
    ],
)
def test_a_bad_calibration_is_named(tmp_path: Path, nodes: dict[str, object], says: str) -> None:
    path = _write(tmp_path / "cam.yaml", **nodes) if nodes else tmp_path / "missing.yaml"
    with pytest.raises(ValueError, match=says):
        Calibration.load(path)


def test_a_text_file_is_not_a_calibration(tmp_path: Path) -> None:
    path = tmp_path / "notes.yaml"
    path.write_text("just some notes\n")
    with pytest.raises(ValueError, match="calibration"):
        Calibration.load(path)


def _as_seen_by(scene: np.ndarray, new: np.ndarray) -> np.ndarray:
    """The pinhole scene (camera matrix K) as a distortion-free camera with matrix `new` shows it."""
    sx, sy = new[0, 0] / K[0, 0], new[1, 1] / K[1, 1]
    affine = np.array([[sx, 0, new[0, 2] - sx * K[0, 2]], [0, sy, new[1, 2] - sy * K[1, 2]]])
    return cv2.warpAffine(scene, affine, (scene.shape[1], scene.shape[0]), borderMode=cv2.BORDER_REPLICATE)


@pytest.mark.parametrize("keep_all", [1.0, None])
def test_undistortion_straightens_what_the_lens_bent_and_the_x_is_found_again(keep_all: float | None) -> None:
    scene = _x_card_near_the_corner()
    seen = _through_the_lens(scene)
    undistort = Undistorter(Calibration(K, D), keep_all)
    restored = undistort(seen)
    new = undistort.new_matrix(640, 480)
    if keep_all is None:
        np.testing.assert_array_equal(new, K)
    else:  # the whole field of view kept: the straightened scene is shown smaller
        assert new[0, 0] < K[0, 0]
    expected = _as_seen_by(scene, new)
    inner = (slice(60, 420), slice(60, 580))  # away from the frame's edge
    before = np.abs(seen[inner].astype(int) - expected[inner]).mean()
    after = np.abs(restored[inner].astype(int) - expected[inner]).mean()
    assert after < 0.25 * before
    detector = MarkDetector()
    assert [d.shape.value for d in detector.detect(scene)] == ["X"]
    assert [d.shape.value for d in detector.detect(restored)] == ["X"]
    with pytest.raises(ValueError, match="not an image"):
        undistort(np.zeros((0,), np.uint8))


def test_keeping_the_whole_view_keeps_a_mark_in_the_corner_of_the_frame() -> None:
    """A strong lens's calibration used with its own camera matrix shows the middle enlarged and cuts the
    frame's edges away, with whatever was there; the default keeps every pixel the camera saw."""
    seen = np.full((480, 640), 200, np.uint8)
    cv2.rectangle(seen, (4, 4), (40, 40), 0, -1)  # something dark in the very corner of the frame
    for keep_all, kept in ((1.0, True), (None, False)):
        restored = Undistorter(Calibration(K, D), keep_all)(seen)
        assert (restored < 100).any() == kept, keep_all


def test_the_service_refuses_a_bad_calibration_in_one_line(tmp_path: Path) -> None:
    bad = _write(tmp_path / "cam.yaml", camera_matrix=K)
    done = subprocess.run(
        [sys.executable, "-m", "services.vision", "--source", "synthetic", "--calibration", str(bad)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "needs distortion_coefficients" in done.stderr
