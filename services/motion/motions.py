"""Motions: per-tick joint targets for stand up, sit down, nod, shake head and walking.

A motion is stepped once per control tick; `step()` returns the targets for that tick (only the
joints the motion drives) or None when it has finished. `posture` is the posture the robot is in
while the motion runs (walking turns into standing once the gait has ended in double support).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from schemas.messages import Action, Posture
from services.motion.gait import Gait, GaitParams, ready_pose
from services.motion.joints import BODY_IDS, HEAD_HOME, HEAD_PAN, HEAD_TILT, NOD_TILT, SHAKE_PAN, STAND, Pose


def ease(s: float) -> float:
    """Cosine ease-in/ease-out on [0, 1]: zero velocity at both ends."""
    s = min(max(s, 0.0), 1.0)
    return (1.0 - math.cos(math.pi * s)) / 2.0


@dataclass
class Interpolation:
    """Move the given joints from `start` to `end` over `duration` seconds."""

    action: Action
    start: Pose
    end: Pose
    duration: float
    dt: float
    posture: Posture = Posture.MOVING
    final_posture: Posture = Posture.STANDING
    _tick: int = 0

    def step(self) -> Pose | None:
        ticks = max(1, round(self.duration / self.dt))
        if self._tick >= ticks:
            return None
        self._tick += 1
        s = ease(self._tick / ticks)
        return {j: self.start[j] + (self.end[j] - self.start[j]) * s for j in self.end if j in self.start}

    def request_stop(self) -> bool:
        """Stand-up and sit-down always finish (stopping half-way leaves the robot crouched)."""
        return False


@dataclass
class HeadGesture:
    """Swing one head joint between two positions a few times, then back to the head's home."""

    action: Action
    joint: int
    start: float
    swings: tuple[float, float]
    posture: Posture
    dt: float
    count: int = 2
    segment: float = 0.3
    final_posture: Posture = Posture.STANDING
    _points: list[float] = field(default_factory=list)
    _tick: int = 0

    def __post_init__(self) -> None:
        self.final_posture = self.posture
        home = HEAD_HOME[self.joint]
        self._points = [self.start, *(list(self.swings) * self.count), home]

    def step(self) -> Pose | None:
        per = max(1, round(self.segment / self.dt))
        seg, k = divmod(self._tick, per)
        if seg >= len(self._points) - 1:
            return None
        self._tick += 1
        a, b = self._points[seg], self._points[seg + 1]
        return {self.joint: a + (b - a) * ease((k + 1) / per)}

    def request_stop(self) -> bool:
        """Return home from wherever the head is now."""
        per = max(1, round(self.segment / self.dt))
        seg, k = divmod(self._tick, per)
        if seg >= len(self._points) - 1:
            return True
        a, b = self._points[seg], self._points[seg + 1]
        here = a + (b - a) * ease(k / per)
        self._points = [here, HEAD_HOME[self.joint]]
        self._tick = 0
        return True


def nod(start: Pose, posture: Posture, dt: float) -> HeadGesture:
    return HeadGesture(Action.NOD, HEAD_TILT, start[HEAD_TILT], NOD_TILT, posture, dt)


def shake_head(start: Pose, posture: Posture, dt: float) -> HeadGesture:
    return HeadGesture(Action.SHAKE_HEAD, HEAD_PAN, start[HEAD_PAN], SHAKE_PAN, posture, dt)


@dataclass
class Walk:
    """Blend into the gait's ready pose, step until stopped, then settle into the stand pose."""

    start: Pose
    params: GaitParams
    blend: float = 0.3
    settle: float = 0.3
    action: Action = Action.WALK_FORWARD
    final_posture: Posture = Posture.STANDING
    gait: Gait = field(init=False)
    _phase: Interpolation | None = field(init=False, default=None)
    _settling: bool = field(init=False, default=False)
    _last: Pose = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.gait = Gait(self.params)
        self._last = ready_pose(self.params)
        self._phase = Interpolation(
            Action.WALK_FORWARD,
            {j: self.start[j] for j in BODY_IDS},
            self._last,
            self.blend,
            self.params.dt,
        )

    @property
    def posture(self) -> Posture:
        return Posture.STANDING if self._settling else Posture.WALKING

    @property
    def stopping(self) -> bool:
        return self.gait.stop_requested or self._settling

    def request_stop(self) -> bool:
        self.action = Action.STOP
        self.gait.request_stop()
        return True

    def resume(self) -> bool:
        """Keep walking after a stop request, if the gait has not ended yet."""
        if self._settling or not self.gait.resume():
            return False
        self.action = Action.WALK_FORWARD
        return True

    def step(self) -> Pose | None:
        if self._phase is not None:
            targets = self._phase.step()
            if targets is not None:
                return targets
            if self._settling:
                return None
            self._phase = None
            if self.gait.stop_requested:  # stopped while blending in: no step at all
                return self._settle_from(self._last)
        frame = self.gait.next()
        if frame is not None:
            self._last = frame.pose
            return frame.pose
        return self._settle_from(self._last)

    def _settle_from(self, pose: Pose) -> Pose | None:
        self._settling = True
        self._phase = Interpolation(
            Action.STOP, pose, {j: STAND[j] for j in BODY_IDS}, self.settle, self.params.dt
        )
        return self._phase.step()


@dataclass
class AfterWalk:
    """A posture goal that arrives while walking: the walk stops (half-cycle boundary, settle to the
    stand pose), then `then` runs (sit down), or nothing more (stand up: the walk ends standing)."""

    walk: Walk
    action: Action
    then: Interpolation | None = None
    _walk_done: bool = field(init=False, default=False)

    def __post_init__(self) -> None:
        self.walk.request_stop()

    @property
    def posture(self) -> Posture:
        if not self._walk_done:
            return self.walk.posture
        return self.then.posture if self.then is not None else Posture.STANDING

    @property
    def final_posture(self) -> Posture:
        return self.then.final_posture if self.then is not None else Posture.STANDING

    def request_stop(self) -> bool:
        """The walk is already stopping; a sit-down, once begun, finishes."""
        return False

    def step(self) -> Pose | None:
        if not self._walk_done:
            targets = self.walk.step()
            if targets is not None:
                return targets
            self._walk_done = True
        return self.then.step() if self.then is not None else None
