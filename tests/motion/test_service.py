"""The motion service as users run it (`python -m services.motion`) on a real Zenoh router."""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from schemas.messages import Action, Health, HealthStatus, MotionGoal, MotionState, Posture
from services.motion.simbus import SimBus
from services.runtime import ServiceContext
from tests.conftest import wait_for

Start = Callable[..., subprocess.Popen[bytes]]


class StateLog:
    def __init__(self, bus: ServiceContext) -> None:
        self.items: list[tuple[float, MotionState]] = []
        self._lock = threading.Lock()
        bus.subscribe(bus.keys.motion_state, MotionState, self._on)

    def _on(self, msg: MotionState) -> None:
        with self._lock:
            self.items.append((time.time(), msg))

    @property
    def last(self) -> MotionState | None:
        with self._lock:
            return self.items[-1][1] if self.items else None

    def wait(self, pred: Callable[[MotionState], bool], timeout: float = 10.0) -> MotionState:
        def check() -> MotionState | None:
            last = self.last
            return last if last is not None and pred(last) else None

        return wait_for(check, timeout)  # type: ignore[return-value]


def send(bus: ServiceContext, action: Action, goal_id: str, *, age: float = 0.0) -> MotionGoal:
    pub = getattr(bus, "_goal_pub", None)
    if pub is None:
        pub = bus.publisher(bus.keys.motion_goal, MotionGoal, block=True)
        bus._goal_pub = pub  # type: ignore[attr-defined]
    return pub.put(MotionGoal(action=action, goal_id=goal_id, stamp=time.time() - age))


def stop(proc: subprocess.Popen[bytes]) -> int:
    proc.send_signal(signal.SIGTERM)
    return proc.wait(10)


@pytest.fixture
def states(bus: ServiceContext) -> StateLog:
    return StateLog(bus)


def test_simulated_robot_stands_walks_and_stops_when_the_reasoner_goes(
    start_service: Start, bus: ServiceContext, states: StateLog
) -> None:
    proc = start_service("motion", env={"HRI_MOTION_SIM": "1"})
    states.wait(lambda s: s.posture == Posture.SITTING and s.bus_ok, 20)
    h = bus.query_health("motion")
    assert h is not None and h.status == HealthStatus.OK and h.detail["sim"] is True
    sim_pid = h.detail["sim_pid"]
    assert Path(f"/proc/{sim_pid}").exists()

    send(bus, Action.WALK_FORWARD, "too-early")
    refused = states.wait(lambda s: s.goal_id == "too-early")
    assert refused.posture == Posture.SITTING and refused.first_write is None

    send(bus, Action.STAND_UP, "up", age=5.0)  # stale: dropped
    goal = send(bus, Action.STAND_UP, "up2")
    moving = states.wait(lambda s: s.goal_id == "up2" and s.first_write is not None, 3)
    assert moving.posture == Posture.MOVING and moving.action == Action.STAND_UP
    assert moving.goal_stamp == goal.stamp and 0 <= moving.first_write - goal.stamp < 0.5
    states.wait(lambda s: s.posture == Posture.STANDING and s.action is None, 3)

    token = bus.session.liveliness().declare_token(bus.keys.alive("reasoner"))
    time.sleep(0.3)
    send(bus, Action.WALK_FORWARD, "go")
    states.wait(lambda s: s.posture == Posture.WALKING, 2)
    for _ in range(3):
        time.sleep(0.4)
        send(bus, Action.WALK_FORWARD, "go")
    assert states.last is not None and states.last.posture == Posture.WALKING
    token.undeclare()
    gone = time.time()
    states.wait(lambda s: s.action == Action.STOP or s.posture == Posture.STANDING, 0.5)
    states.wait(lambda s: s.posture == Posture.STANDING, 1.5)
    assert time.time() - gone < 1.2
    # a late keep-alive of the stopped walk must not restart it
    send(bus, Action.WALK_FORWARD, "go")
    time.sleep(0.5)
    assert states.last is not None and states.last.posture == Posture.STANDING

    # state keeps coming at least every 200 ms
    t_end = time.time()
    time.sleep(1.0)
    stamps = [t for t, _ in states.items if t > t_end]
    assert len(stamps) >= 4 and max(b - a for a, b in itertools.pairwise(stamps)) < 0.3

    h = bus.query_health("motion")
    assert h is not None and h.detail["stale_goals"] == 1
    assert h.detail["loop"]["period_ms_p50"] == pytest.approx(8.0, abs=1.0)
    assert stop(proc) == 0
    assert not Path(f"/proc/{sim_pid}").exists()  # the simulator went with the service
    log = proc.log_path.read_text()  # type: ignore[attr-defined]
    assert "stale goal dropped" in log and "reasoner gone: stopping the walk" in log
    assert "simulated OP2 bus started" in log


def test_walk_stops_without_renewal_and_bad_payloads_are_harmless(
    start_service: Start, bus: ServiceContext, states: StateLog
) -> None:
    proc = start_service("motion", "--renew-timeout", "0.6", env={"HRI_MOTION_SIM": "1"})
    states.wait(lambda s: s.posture == Posture.SITTING and s.bus_ok, 20)
    for junk in (
        b"{not json",
        b'{"action": "fly", "goal_id": "x"}',
        b"",
        b'{"action": "stand_up", "goal_id": ""}',
    ):
        bus.session.put(bus.keys.motion_goal, junk)
    send(bus, Action.STAND_UP, "up")
    states.wait(lambda s: s.posture == Posture.STANDING, 4)
    send(bus, Action.WALK_FORWARD, "go")
    states.wait(lambda s: s.posture == Posture.WALKING, 2)
    started = time.time()
    states.wait(lambda s: s.action == Action.STOP, 2)
    assert 0.5 < time.time() - started < 1.2
    states.wait(lambda s: s.posture == Posture.STANDING, 2)
    h = bus.query_health("motion")
    assert h is not None and h.rejected == 4 and h.detail["goals"]["watchdog_stops"] == 1
    # a stop whose stamp looks stale (the clocks disagree) is carried out, not dropped: no watchdog needed
    send(bus, Action.WALK_FORWARD, "go2")
    states.wait(lambda s: s.posture == Posture.WALKING, 2)
    send(bus, Action.STOP, "halt", age=5.0)
    states.wait(lambda s: s.goal_id == "halt" and s.action == Action.STOP, 2)
    states.wait(lambda s: s.posture == Posture.STANDING, 2)
    h = bus.query_health("motion")
    assert h is not None and h.detail["late_stops"] == 1 and h.detail["goals"]["watchdog_stops"] == 1
    assert "stale_goals" not in h.detail
    assert proc.poll() is None
    assert stop(proc) == 0


def test_missing_port_is_degraded_with_a_hint_and_keeps_running(
    start_service: Start, bus: ServiceContext, states: StateLog, tmp_path
) -> None:  # type: ignore[no-untyped-def]
    missing = str(tmp_path / "ttyUSB9")
    proc = start_service("motion", env={"HRI_MOTION_SIM": "0", "HRI_MOTION_PORT": missing})
    state = states.wait(lambda s: True, 15)
    assert state.posture == Posture.UNKNOWN and not state.bus_ok

    def degraded() -> Health | None:
        h = bus.query_health("motion")
        return h if h is not None and h.status == HealthStatus.DEGRADED else None

    h = wait_for(degraded, 10)
    assert missing in h.detail["error"] and "HRI_MOTION_SIM=1" in h.detail["hint"]  # type: ignore[union-attr]
    send(bus, Action.STAND_UP, "up")
    refused = states.wait(lambda s: s.goal_id == "up")
    assert refused.posture == Posture.UNKNOWN and refused.first_write is None
    assert proc.poll() is None
    assert stop(proc) == 0


@pytest.fixture
def external_sim() -> Iterator[SimBus]:
    sim = SimBus().start()
    try:
        yield sim
    finally:
        sim.stop()


def test_silent_servo_on_a_real_port_is_reported(
    start_service: Start, bus: ServiceContext, states: StateLog, external_sim: SimBus
) -> None:
    proc = start_service("motion", env={"HRI_MOTION_SIM": "0", "HRI_MOTION_PORT": external_sim.path})
    states.wait(lambda s: s.posture == Posture.SITTING and s.bus_ok, 20)
    external_sim.silence(20)
    states.wait(lambda s: not s.bus_ok, 3)

    def degraded() -> Health | None:
        h = bus.query_health("motion")
        return h if h is not None and h.status == HealthStatus.DEGRADED else None

    h = wait_for(degraded, 5)
    assert "ID 20 (head_tilt)" in h.detail["error"]  # type: ignore[union-attr]
    send(bus, Action.NOD, "yes")
    assert states.wait(lambda s: s.goal_id == "yes").first_write is None
    external_sim.revive(20)
    states.wait(lambda s: s.bus_ok, 5)
    send(bus, Action.NOD, "yes2")
    states.wait(lambda s: s.goal_id == "yes2" and s.first_write is not None, 3)
    assert stop(proc) == 0


def test_bad_configuration_is_a_clear_error(start_service: Start) -> None:
    proc = start_service("motion", env={"HRI_MOTION_SIM": "maybe"})
    assert proc.wait(20) == 2
    assert "HRI_MOTION_SIM='maybe'" in proc.log_path.read_text()  # type: ignore[attr-defined]


def test_a_crashed_simulator_is_restarted(
    start_service: Start, bus: ServiceContext, states: StateLog
) -> None:
    proc = start_service("motion", env={"HRI_MOTION_SIM": "1"})
    states.wait(lambda s: s.posture == Posture.SITTING and s.bus_ok, 20)
    h = bus.query_health("motion")
    assert h is not None
    first = h.detail["sim_pid"]
    os.kill(first, signal.SIGKILL)
    states.wait(lambda s: not s.bus_ok, 3)
    states.wait(lambda s: s.bus_ok and s.posture == Posture.SITTING, 10)
    h = bus.query_health("motion")
    assert h is not None and h.status == HealthStatus.OK and h.detail["sim_pid"] != first
    assert stop(proc) == 0
