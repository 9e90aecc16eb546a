"""The vision service: frames from a source -> mark detector -> k-of-n debounce -> `MarkObservation`.

Publishes one `MarkObservation` per processed frame on `hri/<robot>/vision/marks` (an empty list when
no mark is confirmed), stamped with the frame's capture time. A source that cannot be opened, or a
camera that stops delivering, turns health `degraded` (naming the source and the alternatives) and
is retried; the service itself keeps running. With a `synthetic:` source it also follows
`SceneCommand` on `hri/<robot>/vision/scene`. With `lookahead` (off by default) a live source's newer frame is
judged between an older frame's detection steps and published at once if it shows a danger mark (`lookahead.py`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import zenoh

from schemas.access import INPUT_PRIORITIES
from schemas.messages import HealthStatus, MarkObservation, SceneCommand
from services.runtime import ServiceContext, TypedPublisher
from services.vision.calibration import Calibration, Undistorter
from services.vision.debounce import Confirmation, Debouncer
from services.vision.detector import DetectorConfig, MarkDetector, changed_settings
from services.vision.lookahead import Job, LookAhead
from services.vision.preview import PreviewPublisher
from services.vision.sources import (
    ALTERNATIVES,
    EndOfStream,
    Frame,
    FrameSource,
    SourceError,
    SyntheticSource,
    open_source,
)

NAME = "vision"


@dataclass(frozen=True)
class VisionSettings:
    source: str = "camera:0"
    fps: float | None = None  # cap; None: the source's own rate (camera) or its default
    debounce: Confirmation = field(default_factory=Confirmation)
    loop: bool = False  # replay a video file or image folder forever
    retry_s: float = 2.0  # first wait before another attempt to open a missing source ...
    max_retry_s: float = 30.0  # ... doubling up to this
    stall_s: float = 2.0  # a camera silent this long is reported
    seed: int = 0  # synthetic scenes
    detector: DetectorConfig = field(default_factory=DetectorConfig)
    calibration: Calibration | None = None  # the lens's: frames are undistorted before detection
    lookahead: bool = False  # judge a live source's newer frame between an older one's steps (lookahead.py; off)


@dataclass
class _Stats:
    frames: int = 0
    detect_s: float = 0.0
    window_start: float = field(default_factory=time.monotonic)
    window_frames: int = 0
    fps: float = 0.0

    def add(self, detect_s: float) -> None:
        self.frames += 1
        self.window_frames += 1
        self.detect_s += detect_s
        now = time.monotonic()
        if now - self.window_start >= 2.0:
            self.fps = self.window_frames / (now - self.window_start)
            self.window_start, self.window_frames = now, 0


def serve(ctx: ServiceContext, settings: VisionSettings | None = None) -> None:
    settings = settings or VisionSettings()
    # OpenCV's own worker threads off: on a 640x480 frame they cost more than they save (about 6 % more
    # CPU a frame for no shorter wait, measured on round vision25's two-core machine), and a robot's
    # other services need that core; onnxruntime's sessions are on one thread too (`verifier.onnx_session`)
    cv2.setNumThreads(1)
    # express, above commands (the priority the router gives marks anyway): a busy link must not
    # queue a danger sign behind other traffic
    priority = getattr(zenoh.Priority, INPUT_PRIORITIES["vision/marks"].upper())
    pub = ctx.publisher(ctx.keys.vision_marks, MarkObservation, priority=priority, express=True)
    detector = MarkDetector(settings.detector)
    debounce = Debouncer(settings.debounce)
    stats = _Stats()
    ctx.update_detail(
        source=settings.source,
        debounce=str(settings.debounce),
        fps_cap=settings.fps,
        detector=changed_settings(settings.detector) or "defaults",
        calibration=settings.calibration.path if settings.calibration is not None else None,
        lookahead=settings.lookahead,
    )

    holder = _SourceHolder(settings)
    ctx.on_close(holder.close)
    if settings.source.strip().startswith("synthetic:"):

        def on_scene(cmd: SceneCommand) -> None:
            holder.set_shape(cmd)
            ctx.log.info("scene", shape=cmd.shape.value if cmd.shape else None)

        ctx.subscribe(ctx.keys.vision_scene, SceneCommand, on_scene)
    _run(ctx, settings, holder, detector, debounce, pub, stats, PreviewPublisher(ctx))


class _SourceHolder:
    """The current source, built (and rebuilt after a failure) from the settings' spec."""

    def __init__(self, settings: VisionSettings) -> None:
        self.settings = settings
        self.source: FrameSource | None = None
        self._pending: SceneCommand | None = None

    def open(self) -> FrameSource:
        """Build and open the source; SourceError if it cannot be."""
        if self.source is None:
            self.source = open_source(self.settings.source, loop=self.settings.loop, seed=self.settings.seed)
        self.source.open()
        if self._pending is not None:
            self.set_shape(self._pending)
        return self.source

    def set_shape(self, cmd: SceneCommand) -> None:
        if isinstance(self.source, SyntheticSource):
            self.source.set_shape(cmd.shape)
        else:
            self._pending = cmd  # applied once the synthetic source exists

    def close(self) -> None:
        if self.source is not None:
            self.source.close()


def _run(
    ctx: ServiceContext,
    settings: VisionSettings,
    holder: _SourceHolder,
    detector: MarkDetector,
    debounce: Debouncer,
    pub: TypedPublisher[MarkObservation],
    stats: _Stats,
    preview: PreviewPublisher | None = None,
) -> None:
    undistort = Undistorter(settings.calibration) if settings.calibration is not None else None

    def skipped(frame: Frame, error: str) -> None:
        ctx.log.warning("frame skipped", frame=frame.index, error=error)

    frames = LookAhead(
        detector,
        prepare=undistort if undistort is not None else (lambda image: image),
        enabled=settings.lookahead,
        on_skip=skipped,
    )
    opened = False
    retry = _Backoff(settings.retry_s, settings.max_retry_s)
    source: FrameSource | None = None
    pacer = _Pacer()
    last_frame = time.monotonic()

    def newer() -> Frame | None:
        """A newer frame of a live source, if one is due now (between another frame's steps)."""
        nonlocal last_frame
        if source is None or not pacer.due() or not source.fresh():
            return None
        try:
            frame = source.read(timeout=0.0)
        except (SourceError, EndOfStream):  # the loop's own next read meets it again and handles it
            return None
        if frame is not None:
            pacer.took()
            last_frame = time.monotonic()
        return frame

    while not ctx.stopping.is_set():
        if not opened:
            try:
                source = holder.open()
            except SourceError as exc:
                delay, first = retry.next(str(exc))
                ctx.set_status(
                    HealthStatus.DEGRADED, error=str(exc), alternatives=ALTERNATIVES, retry_in_s=delay
                )
                # one warning per distinct failure; the repeats (with a growing wait) at debug level
                (ctx.log.warning if first else ctx.log.debug)(
                    "vision source unavailable, retrying",
                    source=settings.source,
                    error=str(exc),
                    retry_in_s=delay,
                )
                ctx.wait(delay)
                continue
            opened = True
            retry.reset()
            debounce.reset()  # a reopened source starts a new scene
            frames.reset()
            pacer.start(settings.fps or source.default_fps)
            last_frame = time.monotonic()
            ctx.set_status(
                HealthStatus.OK, error=None, alternatives=None, retry_in_s=None, source=settings.source
            )
            ctx.log.info("vision source open", source=settings.source)
        assert source is not None
        job = frames.take_ahead()  # a newer frame already taken (and its coarser levels judged)
        if job is None:
            if ctx.wait(pacer.wait_s()):
                return
            try:
                frame = source.read(timeout=0.5)
            except EndOfStream:
                ctx.log.info("vision source finished", source=settings.source, frames=stats.frames)
                ctx.update_detail(finished=True)
                source.close()
                while not ctx.wait(1.0):
                    pass
                return
            except SourceError as exc:
                ctx.set_status(HealthStatus.DEGRADED, error=str(exc), alternatives=ALTERNATIVES)
                ctx.log.warning("vision source failed, reopening", source=settings.source, error=str(exc))
                source.close()
                opened = False
                ctx.wait(settings.retry_s)
                continue
            now = time.monotonic()
            if frame is None:
                silent = now - last_frame
                if silent > settings.stall_s:
                    ctx.set_status(
                        HealthStatus.DEGRADED,
                        error=f"no frames from {settings.source} for {silent:.1f} s",
                        alternatives=ALTERNATIVES,
                    )
                if silent > 3 * settings.stall_s:
                    ctx.log.warning(
                        "vision source silent, reopening", source=settings.source, silent_s=round(silent, 1)
                    )
                    source.close()
                    opened = False
                continue
            pacer.took()
            last_frame = now
            try:
                job = frames.start(frame)
            except ValueError as exc:
                skipped(frame, str(exc))
                continue
        if ctx.status is not HealthStatus.OK:
            ctx.set_status(HealthStatus.OK, error=None, alternatives=None)
        try:
            job = frames.finish(job, newer)
        except ValueError as exc:
            skipped(job.frame, str(exc))
            continue
        _publish(job, debounce, pub, stats, preview)
        if stats.frames % 15 == 0:
            ctx.update_detail(
                frames=stats.frames,
                fps=round(stats.fps, 1),
                detect_ms_mean=round(1000 * stats.detect_s / stats.frames, 2),
                **frames.counts.as_detail(),
            )


def _publish(
    job: Job,
    debounce: Debouncer,
    pub: TypedPublisher[MarkObservation],
    stats: _Stats,
    preview: PreviewPublisher | None,
) -> None:
    """One detected frame out: through the debounce, as a `MarkObservation`, and to the preview."""
    assert job.found is not None
    stats.add(job.busy_s)
    # here the frame (job.image) and this frame's detections (job.found) are both at hand
    confirmed = debounce.update(job.found)
    obs = pub.put(
        MarkObservation(stamp=job.frame.stamp, frame=stats.frames, marks=[d.to_mark() for d in confirmed])
    )
    if preview is not None:
        preview.offer(job.image, obs.frame, obs.marks, obs.stamp)


class _Pacer:
    """The fps cap: frames are taken at most `cap` times a second (none: as fast as they come)."""

    def __init__(self) -> None:
        self.period = 0.0
        self.next_due = time.monotonic()

    def start(self, cap: float | None) -> None:
        self.period = 1.0 / cap if cap else 0.0
        self.next_due = time.monotonic()

    def due(self) -> bool:
        return time.monotonic() >= self.next_due

    def wait_s(self) -> float:
        return max(0.0, self.next_due - time.monotonic())

    def took(self) -> None:
        """A frame was taken now: the next is due one period after this one's due time (or after now,
        less a period, when the loop has fallen behind: it does not race to catch up)."""
        if self.period:
            self.next_due = max(self.next_due + self.period, time.monotonic() - self.period)


class _Backoff:
    """Waits between attempts to open a missing source: `first_s`, doubling up to `max_s`."""

    def __init__(self, first_s: float, max_s: float) -> None:
        self.first_s, self.max_s = first_s, max(first_s, max_s)
        self._delay = 0.0
        self._last_error: str | None = None

    def next(self, error: str) -> tuple[float, bool]:
        """The wait before the next attempt, and whether this failure is new (worth a warning)."""
        first = error != self._last_error
        self._last_error = error
        self._delay = self.first_s if self._delay == 0 else min(self.max_s, 2 * self._delay)
        return self._delay, first

    def reset(self) -> None:
        self._delay, self._last_error = 0.0, None
