"""The preview image: small, JPEG, boxes in its own pixels, at most `fps` a second, and only while
someone subscribes (in-process, and from the vision service as users run it)."""

from __future__ import annotations

import subprocess
import threading
import time
from collections.abc import Callable

import cv2
import numpy as np
import pytest
import zenoh

from schemas.messages import Health, Mark, MarkObservation, SceneCommand, Shape, VisionPreview
from services.runtime import ServiceContext, client_config
from services.vision.preview import PreviewPublisher, PreviewSettings, decode_jpeg, make_preview
from tests.conftest import wait_for


def test_preview_shrinks_the_frame_and_scales_the_boxes() -> None:
    image = np.zeros((480, 640, 3), np.uint8)
    cv2.rectangle(image, (200, 100), (440, 340), (255, 255, 255), -1)
    mark = Mark(shape=Shape.X, confidence=0.9, box=(200, 100, 240, 240))
    p = make_preview(image, 7, [mark], 123.0, PreviewSettings(width=320, height=240, quality=80))
    assert (p.width, p.height, p.frame, p.stamp) == (320, 240, 7, 123.0)
    assert p.marks[0].box == (100, 50, 120, 120) and p.marks[0].shape is Shape.X
    small = cv2.imdecode(np.frombuffer(decode_jpeg(p), np.uint8), cv2.IMREAD_COLOR)
    assert small.shape == (240, 320, 3)
    assert small[110, 160].mean() > 200 and small[20, 20].mean() < 30  # the white square is where the box says
    tall = make_preview(np.zeros((100, 50), np.uint8), 0, [], 0.0, PreviewSettings())
    assert (tall.width, tall.height) == (50, 100)  # never enlarged


def _session_ctx(endpoint: str, ctx: ServiceContext, name: str) -> ServiceContext:
    return ServiceContext(name, zenoh.open(client_config([endpoint])), ctx.keys)


def test_published_only_while_subscribed_and_at_most_fps(bus: ServiceContext, router_endpoint: str) -> None:
    preview = PreviewPublisher(bus, PreviewSettings(fps=5.0))
    frame = np.full((480, 640, 3), 90, np.uint8)

    def feed(seconds: float) -> int:
        sent, end = 0, time.monotonic() + seconds
        while time.monotonic() < end:
            sent += preview.offer(frame, 0, [], time.time()) is not None
            time.sleep(1 / 30)  # a 30 fps camera
        return sent

    assert feed(0.5) == 0  # nobody listens: nothing encoded, nothing sent
    viewer = _session_ctx(router_endpoint, bus, "viewer")
    try:
        got: list[VisionPreview] = []
        viewer.subscribe(viewer.keys.vision_preview, VisionPreview, got.append)
        wait_for(lambda: preview._pub.matched, timeout=5)
        sent = feed(2.0)
        assert 8 <= sent <= 11, sent  # 5 a second from a 30 fps stream
        wait_for(lambda: len(got) == sent, timeout=5)
    finally:
        viewer.close()
    wait_for(lambda: not preview._pub.matched, timeout=5)
    assert feed(0.5) == 0


@pytest.mark.system
def test_vision_service_previews_only_while_watched(
    bus: ServiceContext, start_service: Callable[..., subprocess.Popen[bytes]], router_endpoint: str
) -> None:
    marks: list[MarkObservation] = []
    bus.subscribe(bus.keys.vision_marks, MarkObservation, marks.append)
    start_service("vision", env={"HRI_VISION_SOURCE": "synthetic:none"})
    wait_for(lambda: len(marks) > 10, timeout=30)

    def previews() -> int:
        health: Health | None = bus.query_health("vision")
        assert health is not None
        return int(health.detail.get("previews", 0))

    assert previews() == 0
    scene = bus.publisher(bus.keys.vision_scene, SceneCommand)
    wait_for(lambda: scene.matched, timeout=10)
    scene.put(SceneCommand(shape=Shape.X))
    got: list[VisionPreview] = []
    lock = threading.Lock()

    def on_preview(p: VisionPreview) -> None:
        with lock:
            got.append(p)

    viewer = _session_ctx(router_endpoint, bus, "viewer")
    try:
        viewer.subscribe(viewer.keys.vision_preview, VisionPreview, on_preview)
        wait_for(lambda: any(m.shape is Shape.X for p in got for m in p.marks), timeout=15)
    finally:
        viewer.close()
    with lock:
        last = next(p for p in reversed(got) if p.marks)
    assert (last.width, last.height) == (320, 240)
    x, y, w, h = last.marks[0].box
    assert 0 <= x and x + w <= 320 and 0 <= y and y + h <= 240
    time.sleep(1.0)  # the undeclaration reaches the vision service
    before = previews()
    time.sleep(1.5)
    assert previews() - before <= 1  # at most one already in flight; then none
