"""A small preview of what the camera sees, for viewers (`VisionPreview` on `hri/<robot>/vision/preview`).

At most `fps` times a second, and only while someone subscribes (Zenoh's matching status), the
frame is shrunk to fit `width` x `height`, JPEG-encoded and published with the confirmed marks'
boxes in the preview's own pixels. With nobody subscribed a frame costs one matching-status check.
"""

from __future__ import annotations

import base64
import time
from dataclasses import dataclass

import cv2
import numpy as np

from schemas.messages import Mark, VisionPreview
from services.runtime import ServiceContext


@dataclass(frozen=True)
class PreviewSettings:
    width: int = 320
    height: int = 240
    fps: float = 5.0
    quality: int = 70
    """JPEG quality, 0..100."""


class PreviewPublisher:
    def __init__(self, ctx: ServiceContext, settings: PreviewSettings | None = None) -> None:
        self.ctx = ctx
        self.settings = settings or PreviewSettings()
        self._pub = ctx.publisher(ctx.keys.vision_preview, VisionPreview)
        self._next = 0.0
        self.published = 0

    def offer(self, image: np.ndarray, frame: int, marks: list[Mark], stamp: float) -> VisionPreview | None:
        """Called with every processed frame; publishes a preview when one is due and wanted."""
        now = time.monotonic()
        if now < self._next or not self._pub.matched:
            return None
        self._next = max(self._next + 1.0 / self.settings.fps, now)
        try:
            msg = self._pub.put(make_preview(image, frame, marks, stamp, self.settings))
        except Exception as exc:  # noqa: BLE001 - a preview is a convenience: never stop the detector for it
            self.ctx.counters.bump("callback_errors")
            self.ctx.log.warning("preview failed", frame=frame, error=str(exc))
            return None
        self.published += 1
        self.ctx.update_detail(previews=self.published)
        return msg


def make_preview(image: np.ndarray, frame: int, marks: list[Mark], stamp: float,
                 settings: PreviewSettings) -> VisionPreview:
    """Shrink `image` to fit the preview size (never enlarge), encode it, and scale the boxes."""
    h, w = image.shape[:2]
    scale = min(settings.width / w, settings.height / h, 1.0)
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    small = cv2.resize(image, size, interpolation=cv2.INTER_AREA) if scale < 1.0 else image
    ok, jpeg = cv2.imencode(".jpg", small, [cv2.IMWRITE_JPEG_QUALITY, settings.quality])
    if not ok:
        raise ValueError(f"JPEG encoding failed for a {w}x{h} frame")
    scaled = [m.model_copy(update={"box": tuple(round(v * scale) for v in m.box)}) for m in marks]
    return VisionPreview(stamp=stamp, frame=frame, width=size[0], height=size[1],
                         jpeg=base64.b64encode(jpeg.tobytes()).decode("ascii"), marks=scaled)


def decode_jpeg(preview: VisionPreview) -> bytes:
    """The preview's JPEG bytes."""
    return base64.b64decode(preview.jpeg)
