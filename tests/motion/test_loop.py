"""The control loop on the simulated bus through the real dynamixel-sdk (no Zenoh): motions reach their
poses on the servos, walking swings the legs alternately, a silent servo is found and named."""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import pytest

from schemas.messages import Action, HealthStatus, Posture
from services.motion.config import MotionSettings
from services.motion.executor import GoalRequest, Snapshot
from services.motion.gait import ready_pose
from services.motion.joints import HEAD_TILT, JOINT_IDS, NOD_TILT, SIT, STAND, pose_error
from services.motion.loop import ControlLoop
from services.motion.simbus import SimBus
from services.runtime import get_logger
from tests.conftest import wait_for


@dataclass
class Probe:
    states: list[tuple[Snapshot, bool]] = field(default_factory=list)
    health: list[tuple[HealthStatus, dict[str, Any]]] = field(default_factory=list)
    details: list[dict[str, Any]] = field(default_factory=list)

    def publish(self, snap: Snapshot, ok: bool) -> None:
        self.states.append((snap, ok))

    def on_health(self, status: HealthStatus | None, **detail: Any) -> None:
        self.details.append(detail)
        if status is not None:
            self.health.append((status, detail))

    @property
    def last(self) -> Snapshot:
        return self.states[-1][0]


@dataclass
class Rig:
    sim: SimBus
    loop: ControlLoop
    probe: Probe

    def goal(self, action: Action, goal_id: str) -> None:
        now = time.time()
        self.loop.submit(GoalRequest(action, goal_id, now, now))

    def posture_is(self, posture: Posture, timeout: float = 5.0) -> None:
        wait_for(lambda: self.probe.states and self.probe.last.posture == posture, timeout)


@contextmanager
def running_loop(
    silent: tuple[int, ...] = (), **settings: float
) -> Iterator[tuple[Rig, threading.Thread]]:
    """A simulated bus (with `silent` IDs not answering from the start) and a control loop on it
    (in a thread), stopped and checked on exit."""
    sim = SimBus().start()
    for jid in silent:
        sim.silence(jid)
    probe = Probe()
    loop = ControlLoop(
        MotionSettings(**{"port": sim.path, "sim": False, "retry_s": 0.3, **settings}),
        log=get_logger("motion-test"),
        port=lambda: sim.path,
        publish=probe.publish,
        health=probe.on_health,
    )
    thread = threading.Thread(target=loop.run, daemon=True)
    thread.start()
    try:
        yield Rig(sim, loop, probe), thread
    finally:
        loop.stop()
        thread.join(5)
        sim.stop()
    assert not thread.is_alive()


@pytest.fixture
def rig() -> Iterator[Rig]:
    with running_loop() as (rig, _thread):
        yield rig


def test_stand_nod_sit_reach_their_poses_on_the_servos(rig: Rig) -> None:
    rig.posture_is(Posture.SITTING)
    # torque goes out as a SYNC_WRITE (no status reply): give the simulator its wire time
    wait_for(lambda: rig.sim.powered and all(rig.sim.torque().values()), 3)
    rig.goal(Action.STAND_UP, "up")
    wait_for(lambda: rig.probe.last.first_write is not None, 5)
    assert rig.probe.last.goal_id == "up"
    rig.posture_is(Posture.STANDING)
    wait_for(lambda: pose_error(rig.sim.present_positions(), STAND) <= 3, 5)
    rig.goal(Action.NOD, "yes")
    tilts = []
    deadline = time.monotonic() + 6  # waits are bounds, not targets: the machine is shared
    while time.monotonic() < deadline:
        tilts.append(rig.sim.present_positions()[HEAD_TILT])
        if rig.probe.last.action is None and rig.probe.last.goal_id == "yes" and len(tilts) > 50:
            break
        time.sleep(0.01)
    assert max(tilts) > NOD_TILT[0] - 40 and min(tilts) < NOD_TILT[1] + 40
    wait_for(lambda: abs(rig.sim.present_positions()[HEAD_TILT] - 2048) <= 3, 5)
    rig.goal(Action.SIT_DOWN, "down")
    rig.posture_is(Posture.MOVING, 3)
    rig.posture_is(Posture.SITTING)
    wait_for(lambda: pose_error(rig.sim.present_positions(), SIT) <= 3, 5)
    assert rig.loop.stats.overruns < rig.loop.stats.ticks / 4  # generous: the machine is shared


def test_walking_swings_the_legs_alternately_and_stops_in_double_support(rig: Rig) -> None:
    rig.posture_is(Posture.SITTING)
    rig.goal(Action.STAND_UP, "up")
    rig.posture_is(Posture.STANDING)
    rig.goal(Action.WALK_FORWARD, "go")
    rig.posture_is(Posture.WALKING, 1)
    t0 = time.time()
    time.sleep(1.6)
    rig.goal(Action.WALK_FORWARD, "go")  # renewal
    time.sleep(0.2)
    rig.goal(Action.STOP, "halt")
    rig.posture_is(Posture.STANDING, 2)
    wait_for(lambda: rig.probe.last.action is None, 2)
    # knee goals on the bus while walking: the right (13) and left (14) knees bend in turn
    log = [(t, g) for t, g in rig.sim.stats.sync_write_log if t > t0 + 0.4]
    ready = ready_pose()
    bent = []
    for _, goals in log:
        right = goals[13] - ready[13]  # right knee bends with larger values
        left = ready[14] - goals[14]  # left knee mirrored
        if max(right, left) > 80:
            side = "R" if right > left else "L"
            if not bent or bent[-1] != side:
                bent.append(side)
    assert len(bent) >= 4 and all(a != b for a, b in itertools.pairwise(bent))
    wait_for(lambda: pose_error(rig.sim.present_positions(), STAND) <= 3, 2)
    assert rig.loop.counters["renewals"] == 1


def test_silent_servo_stops_the_walk_and_is_named(rig: Rig) -> None:
    rig.posture_is(Posture.SITTING)
    rig.goal(Action.STAND_UP, "up")
    rig.posture_is(Posture.STANDING)
    rig.goal(Action.WALK_FORWARD, "go")
    rig.posture_is(Posture.WALKING, 1)
    rig.sim.silence(13)
    wait_for(lambda: not rig.probe.states[-1][1], 2)
    assert rig.probe.last.action == Action.STOP or rig.probe.last.posture == Posture.STANDING
    status, detail = rig.probe.health[-1]
    assert status == HealthStatus.DEGRADED and "ID 13 (r_knee)" in detail["error"]
    rig.posture_is(Posture.STANDING, 2)
    rig.goal(Action.WALK_FORWARD, "again")
    wait_for(lambda: rig.probe.last.goal_id == "again", 1)
    assert rig.probe.last.posture == Posture.STANDING and rig.probe.last.first_write is None
    rig.sim.revive(13)
    wait_for(lambda: rig.probe.states[-1][1], 3)
    assert rig.probe.health[-1][0] == HealthStatus.OK


def test_a_late_status_packet_is_a_bad_read_not_a_broken_bus(rig: Rig) -> None:
    """The SDK takes the first status packet with the right ID as the BULK_READ answer, whatever its
    length; a late reply to an earlier request (a loaded host) must cost one read, not the bus."""
    rig.posture_is(Posture.SITTING)
    rig.goal(Action.STAND_UP, "up")
    rig.posture_is(Posture.STANDING)
    failed_before = len(rig.probe.health)
    rig.sim.stray_reply(JOINT_IDS[0])  # read first: the SDK skips packets of other IDs
    wait_for(lambda: any(d.get("bus", {}).get("rx_corrupt", 0) >= 1 for d in rig.probe.details), 3)
    assert rig.probe.states[-1][1] and rig.probe.last.posture == Posture.STANDING
    assert all(status == HealthStatus.OK for status, _ in rig.probe.health[failed_before:])
    rig.goal(Action.WALK_FORWARD, "go")
    rig.posture_is(Posture.WALKING, 1)


def test_missing_servo_at_start_is_named_and_retried() -> None:
    with running_loop(silent=(17,), retry_s=0.2) as (rig, _thread):
        sim, probe = rig.sim, rig.probe
        wait_for(lambda: probe.health, 5)
        status, detail = probe.health[-1]
        assert status == HealthStatus.DEGRADED
        assert "ID 17 (r_ankle_roll)" in detail["error"] and detail["missing"] == ["ID 17 (r_ankle_roll)"]
        assert probe.last.posture == Posture.UNKNOWN and not probe.states[-1][1]
        sim.revive(17)
        wait_for(lambda: probe.health[-1][0] == HealthStatus.OK, 5)
        wait_for(lambda: probe.last.posture == Posture.SITTING, 2)


def test_a_bus_that_stays_down_is_a_failure_and_recovers() -> None:
    with running_loop(bus_down_s=0.6) as (rig, thread):
        sim, probe = rig.sim, rig.probe
        wait_for(lambda: probe.states and probe.last.posture == Posture.SITTING, 5)
        sim.set_power(False)  # the servos go quiet
        sim.silence(200)  # and so does the CM-740: nothing answers
        wait_for(lambda: not probe.states[-1][1], 2)
        wait_for(lambda: probe.health[-1][0] == HealthStatus.FAILED, 5)
        assert (
            "does not answer" in probe.health[-1][1]["error"]
            or "no valid reply" in probe.health[-1][1]["error"]
        )
        assert probe.last.posture == Posture.UNKNOWN
        sim.revive(200)  # the driver powers the servos again and re-checks them
        wait_for(lambda: probe.health[-1][0] == HealthStatus.OK, 5)
        wait_for(lambda: probe.last.posture == Posture.SITTING and probe.states[-1][1], 2)
        wait_for(lambda: sim.powered and all(sim.torque().values()), 1)
    assert not thread.is_alive()
