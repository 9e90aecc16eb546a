"""Posture bookkeeping: which goal runs, which is refused, and the joint targets of every tick.

Single-threaded: the control loop calls `submit`, `expire` and `tick`. Rules (DESIGN.md and the
lead's contract):
- stand_up from sitting/unknown, sit_down from standing/unknown; the same posture again is
  `already` (nothing moves). nod / shake_head while sitting or standing and idle (a new head
  gesture replaces a running one). walk_forward only from standing; while walking, a walk goal is
  a renewal. stop ends walking at the next half-cycle boundary, or sends the head home.
- A walk goal refused because the robot was not standing yet starts on a renewal that arrives
  once it stands (the reasoner's keep-alive acts as the retry). After a stop goal or a watchdog
  stop, no walk goal id seen before it ever starts walking again: a new goal id is needed.
- stand_up or sit_down while walking stop the walk first (half-cycle boundary, settle to the stand
  pose), then sit down if asked: stopping is always safe, and sitting implies it.
- Anything else is `not_executed`: logged, reported with the goal id and the posture unchanged.
- A goal that produced no servo motion keeps `first_write` None in the state.
- Walking stops by itself when not renewed within `renew_timeout`, when the reasoner is gone,
  or when the bus reports a fault.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from schemas.messages import Action, Posture
from services.motion.gait import GaitParams
from services.motion.joints import HEAD_IDS, JOINT_IDS, SIT, STAND, Pose, pose_error
from services.motion.motions import AfterWalk, HeadGesture, Interpolation, Walk, nod, shake_head

POSE_TOLERANCE = 60
"""Ticks (about 5 degrees): present positions this close to a pose count as being in it."""


class Outcome(StrEnum):
    STARTED = "started"
    RENEWED = "renewed"
    ALREADY = "already"
    NOT_EXECUTED = "not_executed"
    IGNORED = "ignored"
    """A keep-alive of a walk that was stopped: logged, no state change."""


@dataclass(frozen=True)
class GoalRequest:
    action: Action
    goal_id: str
    stamp: float
    received: float
    """time.time() when the service received it."""


@dataclass(frozen=True)
class Snapshot:
    posture: Posture
    action: Action | None
    goal_id: str | None
    goal_stamp: float | None
    first_write: float | None


def classify(present: dict[int, int]) -> Posture:
    if pose_error(present, SIT) <= POSE_TOLERANCE:
        return Posture.SITTING
    if pose_error(present, STAND) <= POSE_TOLERANCE:
        return Posture.STANDING
    return Posture.UNKNOWN


Motion = Interpolation | HeadGesture | Walk | AfterWalk


class MotionExecutor:
    def __init__(self, params: GaitParams, *, stand_time: float = 1.0, renew_timeout: float = 2.0) -> None:
        self.params = params
        self.stand_time = stand_time
        self.renew_timeout = renew_timeout
        self.posture = Posture.UNKNOWN
        self.motion: Motion | None = None
        self.commanded: Pose = {}
        self.goal: GoalRequest | None = None
        self.first_write: float | None = None
        self.awaiting_write = False
        self.last_renewal = 0.0
        self.walk_id: str | None = None
        """The walk goal being executed (renewals carry it)."""
        self.walk_seen: str | None = None
        """The last walk goal received, executed or not."""
        self.stopped_walks: list[str] = []
        self.changed = True

    # ------------------------------------------------------------------ state
    def attach(self, present: dict[int, int]) -> None:
        """The bus is (re)connected: hold the present positions and work out the posture."""
        self.commanded = {j: float(present[j]) for j in JOINT_IDS if j in present}
        self.motion = None
        self.posture = classify(present)
        self.changed = True

    @property
    def action(self) -> Action | None:
        return self.motion.action if self.motion is not None else None

    @property
    def walking(self) -> bool:
        return isinstance(self.motion, Walk)

    def snapshot(self) -> Snapshot:
        goal = self.goal
        return Snapshot(
            posture=self.posture,
            action=self.action,
            goal_id=goal.goal_id if goal else None,
            goal_stamp=goal.stamp if goal else None,
            first_write=self.first_write,
        )

    # ------------------------------------------------------------------ goals
    def submit(self, goal: GoalRequest, now: float, *, fault: str | None = None) -> tuple[Outcome, str]:
        """Handle one goal at monotonic time `now`. `fault` names a bus fault that forbids motion."""
        action = goal.action
        motion = self.motion
        if action == Action.WALK_FORWARD and goal.goal_id in self.stopped_walks:
            return Outcome.IGNORED, "renewal of a walk that was stopped: a new goal id is needed"
        if action == Action.WALK_FORWARD:
            self.walk_seen = goal.goal_id
        if action == Action.WALK_FORWARD and isinstance(motion, Walk) and fault is None:
            if not motion.stopping:
                self.last_renewal = now
                if goal.goal_id == self.walk_id:
                    return Outcome.RENEWED, "walk renewed"
                self.walk_id = goal.goal_id
                return self._accept(goal, motion, "walk continues under a new goal")
            if motion.resume():
                self.last_renewal = now
                self.walk_id = goal.goal_id
                return self._accept(goal, motion, "walk continues")
            if motion.posture == Posture.STANDING:  # settling after a stop: walk again from here
                self.motion, self.posture = None, Posture.STANDING
        if action == Action.STOP:
            self._remember_stopped_walk()  # even a walk goal that was refused: it must not start later
            return self._stop(goal)
        posture_goal = action in (Action.STAND_UP, Action.SIT_DOWN)
        if posture_goal and isinstance(motion, Walk) and not motion.stopping and fault is None:
            self._remember_stopped_walk()
            then = None
            if action == Action.SIT_DOWN:  # from the stand pose the walk settles into
                stand = {j: STAND[j] for j in self.commanded if j not in HEAD_IDS}
                then = Interpolation(
                    Action.SIT_DOWN,
                    stand,
                    {j: SIT[j] for j in stand},
                    self.stand_time,
                    self.params.dt,
                    final_posture=Posture.SITTING,
                )
            return self._accept(goal, AfterWalk(motion, action, then), "stopping the walk first")
        if fault is not None:
            return self._refuse(goal, f"bus fault: {fault}")
        if self.motion is not None and not (
            isinstance(self.motion, HeadGesture) and action in (Action.NOD, Action.SHAKE_HEAD)
        ):
            return self._refuse(goal, f"busy with {self.motion.action.value} ({self.posture.value})")
        if action == Action.STAND_UP:
            if self.posture == Posture.STANDING:
                return self._already(goal, "already standing")
            if self.posture not in (Posture.SITTING, Posture.UNKNOWN):
                return self._refuse(goal, f"cannot stand up while {self.posture.value}")
            return self._accept(goal, self._to_pose(Action.STAND_UP, STAND, Posture.STANDING), "standing up")
        if action == Action.SIT_DOWN:
            if self.posture == Posture.SITTING:
                return self._already(goal, "already sitting")
            if self.posture not in (Posture.STANDING, Posture.UNKNOWN):
                return self._refuse(goal, f"cannot sit down while {self.posture.value}")
            return self._accept(goal, self._to_pose(Action.SIT_DOWN, SIT, Posture.SITTING), "sitting down")
        if action in (Action.NOD, Action.SHAKE_HEAD):
            if self.posture not in (Posture.SITTING, Posture.STANDING):
                return self._refuse(goal, f"cannot move the head while {self.posture.value}")
            make = nod if action == Action.NOD else shake_head
            return self._accept(goal, make(self.commanded, self.posture, self.params.dt), action.value)
        if action == Action.WALK_FORWARD:
            if self.posture != Posture.STANDING:
                return self._refuse(goal, f"cannot walk while {self.posture.value}: stand up first")
            self.last_renewal = now
            self.walk_id = goal.goal_id
            return self._accept(goal, Walk(dict(self.commanded), self.params), "walking")
        return self._refuse(goal, f"unknown action {action}")

    def _stop(self, goal: GoalRequest) -> tuple[Outcome, str]:
        motion = self.motion
        if motion is None:
            return self._already(goal, "nothing to stop")
        if isinstance(motion, Walk) and motion.stopping:
            return self._already(goal, "already stopping")
        if not motion.request_stop():
            return self._refuse(goal, f"{motion.action.value} finishes first")
        return self._accept(goal, motion, "stopping")

    def stop_walking(self) -> bool:
        """Watchdogs and bus faults: end a walk (at the next half-cycle boundary). True if one was running."""
        if isinstance(self.motion, Walk) and not self.motion.stopping:
            self._remember_stopped_walk()
            self.motion.request_stop()
            self.changed = True
            return True
        return False

    def _remember_stopped_walk(self) -> None:
        """A late keep-alive of a stopped walk must never restart it."""
        for goal_id in (self.walk_id, self.walk_seen):
            if goal_id is not None and goal_id not in self.stopped_walks:
                self.stopped_walks.append(goal_id)
        del self.stopped_walks[:-16]

    def expire(self, now: float) -> bool:
        """Stop a walk that the reasoner has not renewed in time. True when it did."""
        if (
            isinstance(self.motion, Walk)
            and not self.motion.stopping
            and now - self.last_renewal > self.renew_timeout
        ):
            return self.stop_walking()
        return False

    def _to_pose(self, action: Action, pose: Pose, final: Posture) -> Interpolation:
        start = {j: self.commanded[j] for j in JOINT_IDS if j not in HEAD_IDS and j in self.commanded}
        end = {j: pose[j] for j in start}
        return Interpolation(action, start, end, self.stand_time, self.params.dt, final_posture=final)

    def _accept(self, goal: GoalRequest, motion: Motion, why: str) -> tuple[Outcome, str]:
        self.motion = motion
        self.goal, self.first_write, self.awaiting_write = goal, None, True
        self.posture = motion.posture
        self.changed = True
        return Outcome.STARTED, why

    def _already(self, goal: GoalRequest, why: str) -> tuple[Outcome, str]:
        self.goal, self.first_write, self.awaiting_write = goal, None, False
        self.changed = True
        return Outcome.ALREADY, why

    def _refuse(self, goal: GoalRequest, why: str) -> tuple[Outcome, str]:
        self.goal, self.first_write, self.awaiting_write = goal, None, False
        self.changed = True
        return Outcome.NOT_EXECUTED, why

    # ------------------------------------------------------------------ ticks
    def tick(self) -> Pose:
        """Advance the running motion one control tick; returns the commanded pose of all joints."""
        motion = self.motion
        if motion is not None:
            targets = motion.step()
            if targets is None:
                self.posture = motion.final_posture
                self.motion = None
                self.changed = True
            else:
                self.commanded.update(targets)
                posture = motion.posture
                if posture != self.posture:
                    self.posture = posture
                    self.changed = True
        return self.commanded

    def written(self, when: float) -> None:
        """The SYNC_WRITE of this tick went out at `when` (time.time())."""
        if self.awaiting_write:
            self.first_write = when
            self.awaiting_write = False
            self.changed = True
