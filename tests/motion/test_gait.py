"""The walking gait: leg IK, alternating swings, stopping in double support, joint limits."""

from __future__ import annotations

import math

import pytest

from services.motion.gait import ANKLE, CALF, LEG, THIGH, Gait, GaitParams, leg_ik
from services.motion.joints import JOINTS


def foot_position(angles: tuple[float, ...]) -> tuple[float, float]:
    """Planar forward kinematics (sagittal plane) of hip pitch, knee, ankle: ankle joint (x, z)."""
    hip, knee = math.radians(angles[2]), math.radians(angles[3])
    x = -THIGH * math.sin(hip) - CALF * math.sin(hip + knee)
    z = -THIGH * math.cos(hip) - CALF * math.cos(hip + knee)
    return x, z


def test_straight_leg_is_all_zero() -> None:
    ik = leg_ik(0.0, 0.0, 0.0)
    assert ik is not None and all(abs(a) < 1e-6 for a in ik.values)


@pytest.mark.parametrize(("x", "z"), [(0.0, 20.0), (15.0, 30.0), (-25.0, 60.0)])
def test_ik_reaches_the_foot_target_and_keeps_the_foot_flat(x: float, z: float) -> None:
    ik = leg_ik(x, 0.0, z)
    assert ik is not None
    fx, fz = foot_position(ik.values)
    # the IK's x axis points forward with positive hip pitch leaning back: compare magnitudes and height
    assert abs(abs(fx) - abs(x)) < 0.5
    assert abs(-fz - (LEG - ANKLE - z)) < 0.5
    assert abs(ik.values[2] + ik.values[3] + ik.values[4]) < 1e-6  # sole parallel to the ground


def test_unreachable_target_is_none() -> None:
    assert leg_ik(0.0, 0.0, -50.0) is None  # longer than the leg


def lifted(gait: Gait, ticks: int) -> list[str]:
    """Which foot is in the air at each tick: 'L', 'R' or '-' (double support)."""
    out = []
    for _ in range(ticks):
        frame = gait.next()
        assert frame is not None
        assert not (frame.left_lift > 0 and frame.right_lift > 0)
        out.append("L" if frame.left_lift > 0 else "R" if frame.right_lift > 0 else "-")
    return out


def test_legs_swing_alternately() -> None:
    params = GaitParams()
    seq = lifted(Gait(params), round(2 * params.period / params.dt))
    phases = [c for i, c in enumerate(seq) if c != "-" and (i == 0 or seq[i - 1] != c)]
    assert phases == ["L", "R", "L", "R"]
    assert 0.8 < seq.count("L") / seq.count("R") < 1.25
    assert seq[0] == "-"  # a walk starts in double support


def test_feet_move_forward_alternately_while_walking() -> None:
    gait = Gait(GaitParams(stride=15.0))
    xs = [(f.left_x, f.right_x) for f in (gait.next() for _ in range(150))]
    assert max(x for x, _ in xs) == pytest.approx(15.0)
    assert min(x for x, _ in xs) == pytest.approx(-15.0)
    # when the left foot is in front the right one is behind, and the other way round
    assert all(abs(left + right) < 1e-9 for left, right in xs)


@pytest.mark.parametrize("stop_at", [1, 20, 37, 38, 60, 74, 100])
def test_stop_ends_at_a_half_cycle_boundary_in_double_support(stop_at: int) -> None:
    params = GaitParams()
    gait = Gait(params)
    last = None
    for _ in range(stop_at):
        last = gait.next()
    gait.request_stop()
    ticks = 0
    while (frame := gait.next()) is not None:
        last = frame
        ticks += 1
        assert ticks < 2 * params.half / params.dt + 2
    assert gait.finished and last is not None
    assert gait.time in (0.0, params.half)
    assert last.double_support
    assert abs(last.left_x) < 1e-6 and abs(last.right_x) < 1e-6  # feet side by side


def test_a_pending_stop_can_be_cancelled() -> None:
    gait = Gait(GaitParams())
    for _ in range(10):
        gait.next()
    gait.request_stop()
    assert gait.resume()
    for _ in range(300):
        assert gait.next() is not None


def test_every_gait_frame_is_inside_the_joint_limits() -> None:
    gait = Gait(GaitParams(stride=20.0))
    for _ in range(round(3 * 0.6 / 0.008)):
        frame = gait.next()
        assert frame is not None
        for jid, value in frame.pose.items():
            joint = JOINTS[jid]
            assert joint.lo <= value <= joint.hi, (joint.name, value)
