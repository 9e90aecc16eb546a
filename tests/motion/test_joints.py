"""Present joint positions on the bus: the motion service on the simulated OP2 publishes them at the
documented rate while someone subscribes, and they are the robot's pose."""

from __future__ import annotations

import math
import statistics
import threading
import time
from collections.abc import Callable
from subprocess import Popen

from schemas.messages import JointPositions, MotionState, Posture
from services.motion.joints import JOINT_IDS, JOINTS, SIT
from services.motion.present import RATE_HZ, joint_positions
from services.runtime import ServiceContext
from tests.conftest import wait_for


def test_joint_positions_message_converts_ticks_to_radians_from_the_centre() -> None:
    msg = joint_positions({20: 2048, 1: 1024, 13: 3072}, stamp=12.5)
    assert msg.ids == [1, 13, 20] and msg.names == ["r_shoulder_pitch", "r_knee", "head_tilt"]
    assert msg.ticks == [1024, 3072, 2048]
    assert msg.radians == [round(-math.pi / 2, 5), round(math.pi / 2, 5), 0.0] and msg.stamp == 12.5


def test_motion_publishes_the_sitting_pose_at_the_documented_rate(
    bus: ServiceContext, start_service: Callable[..., Popen[bytes]]
) -> None:
    got: list[tuple[float, JointPositions]] = []
    lock = threading.Lock()
    states: list[MotionState] = []
    bus.subscribe(bus.keys.motion_state, MotionState, states.append)
    start_service("motion", env={"HRI_MOTION_SIM": "1"})
    wait_for(lambda: states and states[-1].posture is Posture.SITTING, timeout=30)

    def on_joints(msg: JointPositions) -> None:
        with lock:
            got.append((time.monotonic(), msg))

    bus.subscribe(bus.keys.motion_joints, JointPositions, on_joints)
    wait_for(lambda: len(got) >= 5, timeout=10)
    time.sleep(2.0)
    with lock:
        window = list(got)
    msgs = [m for _, m in window]
    assert all(m.ids == list(JOINT_IDS) and m.names == [JOINTS[i].name for i in JOINT_IDS] for m in msgs)
    last = msgs[-1]
    for jid, ticks in zip(last.ids, last.ticks, strict=True):
        assert abs(ticks - SIT[jid]) <= 40, (JOINTS[jid].name, ticks, SIT[jid])  # the simulated servos hold the pose
    # The rate: the median gap between stamps is the period (a loaded machine delays some, never bursts).
    gaps = [b.stamp - a.stamp for a, b in zip(msgs, msgs[1:], strict=False)]
    assert abs(statistics.median(gaps) - 1 / RATE_HZ) < 0.25 / RATE_HZ, statistics.median(gaps)
    assert all(g > 0 for g in gaps)
    assert [m.seq for m in msgs] == list(range(msgs[0].seq, msgs[0].seq + len(msgs)))  # none lost
