"""Posture bookkeeping without a bus: what runs, what is refused, watchdogs."""

from __future__ import annotations

import itertools

from schemas.messages import Action, Posture
from services.motion.executor import GoalRequest, MotionExecutor, Outcome
from services.motion.gait import GaitParams
from services.motion.joints import JOINTS, SIT, STAND, clamp_pose, pose_error

_ids = itertools.count()


def goal(action: Action, goal_id: str | None = None) -> GoalRequest:
    return GoalRequest(action, goal_id or f"g{next(_ids)}", 1.0, 1.0)


def sitting() -> MotionExecutor:
    ex = MotionExecutor(GaitParams(), stand_time=0.2, renew_timeout=1.0)
    ex.attach({j: int(v) for j, v in SIT.items()})
    return ex


def run(ex: MotionExecutor, ticks: int) -> None:
    for _ in range(ticks):
        ex.tick()


def standing() -> MotionExecutor:
    ex = sitting()
    ex.submit(goal(Action.STAND_UP), 0.0)
    run(ex, 30)
    return ex


def test_starts_sitting_and_stands_up_through_moving() -> None:
    ex = sitting()
    assert ex.posture == Posture.SITTING
    outcome, _ = ex.submit(goal(Action.STAND_UP, "up"), 0.0)
    assert outcome == Outcome.STARTED and ex.posture == Posture.MOVING and ex.action == Action.STAND_UP
    assert ex.awaiting_write
    ex.written(123.0)
    assert ex.snapshot().first_write == 123.0
    run(ex, 30)
    assert ex.posture == Posture.STANDING and ex.action is None
    assert pose_error({j: round(v) for j, v in ex.commanded.items()}, STAND) <= 1


def test_walk_while_sitting_is_reported_not_executed() -> None:
    ex = sitting()
    outcome, why = ex.submit(goal(Action.WALK_FORWARD, "w"), 0.0)
    assert outcome == Outcome.NOT_EXECUTED and "stand up first" in why
    snap = ex.snapshot()
    assert (snap.posture, snap.goal_id, snap.first_write, ex.awaiting_write) == (
        Posture.SITTING,
        "w",
        None,
        False,
    )


def test_same_posture_again_is_already_done() -> None:
    ex = sitting()
    assert ex.submit(goal(Action.SIT_DOWN), 0.0)[0] == Outcome.ALREADY
    assert standing().submit(goal(Action.STAND_UP), 0.0)[0] == Outcome.ALREADY


def test_busy_while_standing_up_and_stop_does_not_interrupt_it() -> None:
    ex = sitting()
    ex.submit(goal(Action.STAND_UP), 0.0)
    assert ex.submit(goal(Action.NOD), 0.0)[0] == Outcome.NOT_EXECUTED
    assert ex.submit(goal(Action.STOP), 0.0)[0] == Outcome.NOT_EXECUTED
    run(ex, 30)
    assert ex.posture == Posture.STANDING


def test_head_gestures_keep_the_posture() -> None:
    ex = sitting()
    assert ex.submit(goal(Action.NOD), 0.0)[0] == Outcome.STARTED
    assert ex.posture == Posture.SITTING and ex.action == Action.NOD
    tilts = []
    for _ in range(250):
        tilts.append(ex.tick()[20])
    assert max(tilts) > 2300 and min(tilts) < 2020 and ex.action is None
    assert abs(tilts[-1] - 2048) < 1


def test_walk_renewal_stop_and_no_restart_from_a_late_keepalive() -> None:
    ex = standing()
    assert ex.submit(goal(Action.WALK_FORWARD, "w1"), 0.0)[0] == Outcome.STARTED
    assert ex.posture == Posture.WALKING
    run(ex, 50)
    assert ex.submit(goal(Action.WALK_FORWARD, "w1"), 0.5)[0] == Outcome.RENEWED
    assert ex.submit(goal(Action.STOP, "s1"), 0.6)[0] == Outcome.STARTED
    assert ex.action == Action.STOP
    assert ex.submit(goal(Action.WALK_FORWARD, "w1"), 0.7)[0] == Outcome.IGNORED
    assert ex.snapshot().goal_id == "s1"
    run(ex, 200)
    assert ex.posture == Posture.STANDING and ex.action is None
    assert ex.submit(goal(Action.WALK_FORWARD, "w1"), 1.0)[0] == Outcome.IGNORED
    assert ex.submit(goal(Action.WALK_FORWARD, "w2"), 1.0)[0] == Outcome.STARTED


def test_walk_without_renewal_stops_by_itself() -> None:
    ex = standing()
    ex.submit(goal(Action.WALK_FORWARD, "w"), 10.0)
    assert not ex.expire(10.9)
    ex.submit(goal(Action.WALK_FORWARD, "w"), 10.9)
    assert not ex.expire(11.8)
    assert ex.expire(12.0)
    assert ex.action == Action.STOP
    run(ex, 200)
    assert ex.posture == Posture.STANDING


def test_bus_fault_refuses_motion_but_not_stop() -> None:
    ex = standing()
    ex.submit(goal(Action.WALK_FORWARD, "w"), 0.0)
    assert ex.submit(goal(Action.NOD), 0.0, fault="ID 9 silent")[0] == Outcome.NOT_EXECUTED
    assert ex.submit(goal(Action.STOP), 0.0, fault="ID 9 silent")[0] == Outcome.STARTED


def test_stand_up_from_unknown_posture() -> None:
    ex = MotionExecutor(GaitParams(), stand_time=0.2)
    ex.attach({j: 2048 for j in SIT})
    assert ex.posture == Posture.UNKNOWN
    assert ex.submit(goal(Action.NOD), 0.0)[0] == Outcome.NOT_EXECUTED
    assert ex.submit(goal(Action.STAND_UP), 0.0)[0] == Outcome.STARTED
    run(ex, 30)
    assert ex.posture == Posture.STANDING


def test_joint_limits_clamp_every_goal() -> None:
    wild = {jid: -500.0 if jid % 2 else 9000.0 for jid in JOINTS}
    clamped = clamp_pose(wild)
    assert all(JOINTS[j].lo <= v <= JOINTS[j].hi for j, v in clamped.items())
    assert clamped[20] == JOINTS[20].hi and clamped[19] == JOINTS[19].lo


def test_a_refused_walk_starts_on_renewal_once_standing_unless_stopped() -> None:
    ex = sitting()
    ex.submit(goal(Action.STAND_UP), 0.0)
    assert ex.submit(goal(Action.WALK_FORWARD, "w"), 0.0)[0] == Outcome.NOT_EXECUTED  # still standing up
    run(ex, 30)
    assert ex.submit(goal(Action.WALK_FORWARD, "w"), 0.5)[0] == Outcome.STARTED  # the keep-alive retries it
    ex.submit(goal(Action.STOP), 0.6)
    run(ex, 200)
    assert ex.submit(goal(Action.WALK_FORWARD, "x"), 1.0)[0] == Outcome.STARTED
    ex.submit(goal(Action.STOP), 1.1)
    run(ex, 200)
    assert ex.submit(goal(Action.SIT_DOWN), 2.0)[0] == Outcome.STARTED
    assert ex.submit(goal(Action.WALK_FORWARD, "y"), 2.0)[0] == Outcome.NOT_EXECUTED
    ex.submit(goal(Action.STOP), 2.1)  # refused (sit-down finishes) but it still cancels walk "y"
    run(ex, 30)
    ex.submit(goal(Action.STAND_UP), 3.0)
    run(ex, 30)
    assert ex.submit(goal(Action.WALK_FORWARD, "y"), 4.0)[0] == Outcome.IGNORED


def test_sit_down_while_walking_stops_first_then_sits() -> None:
    ex = standing()
    ex.submit(goal(Action.WALK_FORWARD, "w"), 0.0)
    run(ex, 60)
    assert ex.submit(goal(Action.SIT_DOWN, "down"), 0.5)[0] == Outcome.STARTED
    assert ex.action == Action.SIT_DOWN and ex.posture == Posture.WALKING
    assert ex.submit(goal(Action.WALK_FORWARD, "w"), 0.6)[0] == Outcome.IGNORED
    assert ex.submit(goal(Action.STOP), 0.6)[0] == Outcome.NOT_EXECUTED  # already stopping, then sitting
    seen = []
    for _ in range(400):
        ex.tick()
        if not seen or seen[-1] != ex.posture:
            seen.append(ex.posture)
    assert seen == [Posture.WALKING, Posture.STANDING, Posture.MOVING, Posture.SITTING]
    assert pose_error({j: round(v) for j, v in ex.commanded.items()}, SIT) <= 1


def test_stand_up_while_walking_ends_standing() -> None:
    ex = standing()
    ex.submit(goal(Action.WALK_FORWARD, "w"), 0.0)
    run(ex, 60)
    assert ex.submit(goal(Action.STAND_UP), 0.5)[0] == Outcome.STARTED
    run(ex, 200)
    assert ex.posture == Posture.STANDING and ex.action is None
