"""A camera's lens calibration, and frames undistorted with it before detection.

A wide-angle lens bends the straight bars and sides the detector's shape tests expect (the vision
README: through a strong simulated lens the detector missed 429 tuning marks of 1,500 against 251).
`--calibration FILE` / `HRI_VISION_CALIBRATION` names the camera's calibration in OpenCV's FileStorage
format (YAML or JSON), as OpenCV's calibration sample and ROS's `camera_calibration` write it:

    camera_matrix: !!opencv-matrix   (3x3: fx 0 cx / 0 fy cy / 0 0 1)
    distortion_coefficients: !!opencv-matrix   (1x4, 1x5, 1x8 ...: k1 k2 p1 p2 [k3 ...])
    image_width: 640        (optional: the resolution it was made at; other frame sizes are scaled)
    image_height: 480

Each frame is then remapped to what a distortion-free camera with the same field of view would see
(`Undistorter`; `cv2.initUndistortRectifyMap` once per frame size, `cv2.remap` per frame: about a
millisecond at 640x480).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

DISTORTION_KEYS = ("distortion_coefficients", "dist_coeffs")


@dataclass(frozen=True)
class Calibration:
    camera_matrix: np.ndarray  # 3x3, float64
    distortion: np.ndarray  # 1xN, float64
    size: tuple[int, int] | None = None  # (width, height) it was made at, if the file says
    path: str = ""

    @classmethod
    def load(cls, path: Path | str) -> Calibration:
        """The calibration in `path`. ValueError naming the file and what is wrong with it."""
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"calibration {path}: no such file")
        try:
            fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        except (cv2.error, SystemError):  # OpenCV's parser error surfaces as either
            raise ValueError(
                f"calibration {path}: not an OpenCV FileStorage file (YAML, JSON or XML)"
            ) from None
        try:
            if not fs.isOpened():
                raise ValueError(f"calibration {path}: not an OpenCV FileStorage file")
            matrix = fs.getNode("camera_matrix").mat()
            distortion = next(
                (d for d in (fs.getNode(k).mat() for k in DISTORTION_KEYS) if d is not None), None
            )
            width, height = fs.getNode("image_width").real(), fs.getNode("image_height").real()
        finally:
            fs.release()
        if matrix is None or matrix.shape != (3, 3):
            raise ValueError(f"calibration {path}: needs camera_matrix, a 3x3 matrix")
        if distortion is None or distortion.size not in (4, 5, 8, 12, 14):
            raise ValueError(
                f"calibration {path}: needs distortion_coefficients (or dist_coeffs): 4, 5, 8, 12 or 14 numbers"
            )
        if matrix[0, 0] <= 0 or matrix[1, 1] <= 0:
            raise ValueError(f"calibration {path}: the focal lengths (fx, fy) must be positive")
        size = (int(width), int(height)) if width > 0 and height > 0 else None
        return cls(matrix.astype(np.float64), distortion.reshape(1, -1).astype(np.float64), size, str(path))

    def matrix_for(self, width: int, height: int) -> np.ndarray:
        """The camera matrix for frames of this size (scaled from the calibrated size, if it is known)."""
        if self.size is None or self.size == (width, height):
            return self.camera_matrix
        sx, sy = width / self.size[0], height / self.size[1]
        return np.diag([sx, sy, 1.0]) @ self.camera_matrix


@dataclass
class Undistorter:
    """Frames remapped to a distortion-free camera that keeps the whole field of view.

    `keep_all` 1.0 (the default): the new camera matrix is `cv2.getOptimalNewCameraMatrix(..., alpha=1)`,
    which keeps every pixel the camera saw (the corners of a barrel lens's frame stay in the frame; the
    middle is shown a little smaller). 0.0 keeps only pixels that are valid everywhere; None keeps the
    calibration's own camera matrix, which shows the middle at the lens's magnification and cuts the
    edges: through a strong wide-angle lens that cut most of the tuning generator's marks out of view
    (the vision README, "A wide-angle lens")."""

    calibration: Calibration
    keep_all: float | None = 1.0
    _maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    _matrices: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)

    def new_matrix(self, width: int, height: int) -> np.ndarray:
        """The camera matrix of the undistorted frames of this size."""
        if (width, height) not in self._matrices:
            k = self.calibration.matrix_for(width, height)
            if self.keep_all is not None:
                k, _ = cv2.getOptimalNewCameraMatrix(k, self.calibration.distortion, (width, height), self.keep_all)
            self._matrices[(width, height)] = k
        return self._matrices[(width, height)]

    def __call__(self, image: np.ndarray) -> np.ndarray:
        """`image` undistorted; ValueError for something that is not an image."""
        if image.ndim not in (2, 3) or image.size == 0:
            raise ValueError(f"not an image: array of shape {image.shape}")
        h, w = image.shape[:2]
        maps = self._maps.get((w, h))
        if maps is None:
            k = self.calibration.matrix_for(w, h)
            maps = cv2.initUndistortRectifyMap(k, self.calibration.distortion, None, self.new_matrix(w, h), (w, h),
                                               cv2.CV_16SC2)
            self._maps[(w, h)] = maps
        return cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
