"""Draw detections on a copy of an image, so a person can see what the detector saw."""

from __future__ import annotations

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision.detector import Detection

COLOURS: dict[Shape, tuple[int, int, int]] = {
    Shape.X: (0, 0, 255),
    Shape.TRIANGLE: (0, 165, 255),
    Shape.O: (0, 200, 0),
}


def annotate(image: np.ndarray, detections: list[Detection]) -> np.ndarray:
    out = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    for d in detections:
        x, y, w, h = d.box
        colour = COLOURS[d.shape]
        cv2.rectangle(out, (x, y), (x + w, y + h), colour, 2)
        label = f"{d.shape.value} {d.confidence:.2f}"
        cv2.putText(out, label, (x, max(14, y - 5)), cv2.FONT_HERSHEY_SIMPLEX, 0.5, colour, 2, cv2.LINE_AA)
    return out
