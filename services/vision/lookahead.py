"""A danger mark need not wait behind an ordinary frame: between one frame's steps, look at the newest.

The vision loop is one core's work, and where an ordinary frame of a cluttered room costs more than the
camera's frame period, an X held up just after such a frame was taken waits for all of it, its full
resolution level and its proposer, before its own frame is even taken. Yet the detector confirms a
held-up X on the coarser levels in 3-7 ms (`DetectorConfig.danger_first`).

So on a live source (a camera, the synthetic scene; `FrameSource.fresh`), while a frame is detected, a
newer frame that is due is taken between two of its steps (`MarkDetector.steps`: each pyramid level,
each judged component, each verifier call, the proposer) and its coarser levels are judged at once, by
a second detector sharing the networks (`MarkDetector.twin`):
- if they confirm an X or a TRIANGLE, that newer frame is the one published, now, and the older frame is
  dropped unpublished (what it could still add is older than a danger mark already seen);
- otherwise the newer frame waits (`ahead`), its coarser levels done, and is finished after the older
  one; a still newer frame replaces it (the loop always catches up with the newest, as before).
Every frame that is published gets exactly the detections `MarkDetector.detect` gives it. Files and
folders are never looked ahead in (their frames are all taken, in order).

Off by default (the service's `--lookahead`): on round vision26's machine the loop kept up with a 30 fps
camera in the running stack (27 ms a frame) and the look ahead did not lower the stop's p99; standalone,
with frames due faster than the loop finishes them, it cut X shown -> published from p50 18 / max 36 ms
to 14 / 26 ms (docs/experiments/vision-rounds.md, "Vision26").
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from services.vision.debounce import DANGER_SHAPES
from services.vision.detector import Detection, MarkDetector, Step, Steps
from services.vision.sources import Frame


@dataclass
class Job:
    """One frame in flight: its detector (no other frame's steps run on it meanwhile) and its steps."""

    frame: Frame
    image: np.ndarray  # what the detector sees (the frame, undistorted if the lens is calibrated)
    detector: MarkDetector
    steps: Steps
    busy_s: float = 0.0  # time spent in its steps so far
    found: list[Detection] | None = None  # its detections, once its steps have ended

    def step(self) -> Step | None:
        """Run its next step; None once it has ended (then `found` is set)."""
        if self.found is not None:
            return None
        t0 = time.perf_counter()
        try:
            return next(self.steps)
        except StopIteration as done:
            self.found = done.value
            return None
        finally:
            self.busy_s += time.perf_counter() - t0


@dataclass
class Counts:
    looks: int = 0  # newer frames taken between another frame's steps
    dangers: int = 0  # of them, published at once for a danger mark (an older frame dropped)
    replaced: int = 0  # of them, replaced by a still newer frame before being finished
    skipped: int = 0  # of them, refused by the detector (`ValueError`): dropped

    def as_detail(self) -> dict[str, int]:
        return {
            "lookahead_looks": self.looks,
            "lookahead_dangers": self.dangers,
            "lookahead_replaced": self.replaced,
            "lookahead_skipped": self.skipped,
        }


@dataclass
class LookAhead:
    """The frames in flight: the one being finished, and at most one newer one (`ahead`)."""

    detector: MarkDetector
    prepare: Callable[[np.ndarray], np.ndarray] = lambda image: image
    enabled: bool = True
    on_skip: Callable[[Frame, str], None] = lambda frame, error: None
    ahead: Job | None = field(default=None, init=False)
    counts: Counts = field(default_factory=Counts, init=False)
    _free: list[MarkDetector] = field(default_factory=list, init=False)  # detectors no frame is on

    def __post_init__(self) -> None:
        # looking ahead needs coarser levels judged first: without danger_first (or without the verifier,
        # which confirms a level's marks), or with one level, a frame's steps never pause at `Step.FINE`
        config = self.detector.config
        self.enabled = (
            self.enabled and config.danger_first and self.detector.verifier is not None and len(config.levels) > 1
        )
        self._free = [self.detector, self.detector.twin()] if self.enabled else [self.detector]

    def start(self, frame: Frame) -> Job:
        """A job for `frame`; ValueError if the detector refuses its image (nothing is then in flight)."""
        detector = self._free.pop()
        try:
            image = self.prepare(frame.image)
            return Job(frame, image, detector, detector.steps(image))
        except ValueError:
            self._free.append(detector)
            raise

    def take_ahead(self) -> Job | None:
        """The newer frame waiting ahead (its coarser levels judged), to be finished next; None if none."""
        job, self.ahead = self.ahead, None
        return job

    def finish(self, job: Job, newer: Callable[[], Frame | None]) -> Job:
        """Finish `job`, taking a newer frame from `newer` between its steps when one is due (None when
        not): the job to publish, `job` itself or a newer frame with a danger mark (`job` dropped).
        ValueError from `job`'s detector, or anything `newer` raises, propagates (`job` is dropped)."""
        try:
            while job.step() is not None:
                if not self.enabled:
                    continue
                frame = newer()
                if frame is None:
                    continue
                ahead = self._look(frame)
                if ahead is not None and ahead.found is not None and _danger(ahead.found):
                    self.ahead = None
                    self.counts.dangers += 1
                    self._drop(job)
                    self._free.append(ahead.detector)
                    return ahead
        except BaseException:
            self._drop(job)
            raise
        self._free.append(job.detector)
        return job

    def reset(self) -> None:
        """Forget the frame waiting ahead (the source was reopened: a new scene)."""
        if self.ahead is not None:
            self._drop(self.ahead)
            self.ahead = None

    def _look(self, frame: Frame) -> Job | None:
        """Judge `frame`'s coarser levels (up to `Step.FINE`, or to its end on a danger mark) and keep it
        ahead, in place of the one there; None if the detector refused it."""
        self.counts.looks += 1
        if self.ahead is not None:
            self.counts.replaced += 1
            self._drop(self.ahead)
            self.ahead = None
        try:
            job = self.start(frame)
        except ValueError as exc:
            self._skipped(frame, exc)
            return None
        try:
            while (step := job.step()) is not None and step is not Step.FINE:
                pass
        except ValueError as exc:
            self._drop(job)
            self._skipped(frame, exc)
            return None
        self.ahead = job
        return job

    def _skipped(self, frame: Frame, exc: ValueError) -> None:
        self.counts.skipped += 1
        self.on_skip(frame, str(exc))

    def _drop(self, job: Job) -> None:
        job.steps.close()
        self._free.append(job.detector)


def _danger(found: list[Detection]) -> bool:
    return any(d.shape in DANGER_SHAPES for d in found)
