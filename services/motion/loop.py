"""The 8 ms control loop: connect to the bus, then every tick apply goals, one SYNC_WRITE, one BULK_READ.

Runs in one thread that alone touches the port. Goals come in through `submit` (any thread) and are
applied at the start of the next tick; a new goal wakes the loop so that its first SYNC_WRITE does
not wait for the rest of the period. Bus trouble is handled here:
- a port that does not exist or cannot be opened: `degraded`, naming the port, retried;
- joints that do not answer at start: `degraded`, naming ID and joint, retried;
- a servo that stops answering while running: found by ping, dropped from the BULK_READ, walking
  stopped, `bus_ok` false and `degraded` naming it; pinged again every `retry_s` while not walking;
- reads failing for `bus_down_s` (nothing answers) or the port vanishing: `failed`, reconnect.
"""

from __future__ import annotations

import queue
import statistics
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from schemas.messages import Action, HealthStatus, Posture
from services.motion.config import MotionSettings
from services.motion.driver import BusError, JointsMissing, NoAnswer, Op2Bus, PortLost, PortMissing
from services.motion.executor import GoalRequest, MotionExecutor, Outcome, Snapshot
from services.motion.gait import GaitParams
from services.motion.joints import CM740_ID, JOINT_IDS, clamp_pose, describe

GAINS: dict[int, tuple[int, int, int]] = {jid: (0, 0, 32) for jid in JOINT_IDS}
"""D, I, P per joint (MX-28 defaults)."""
BAD_READS_FOR_NOT_OK = 5
"""Consecutive failed BULK_READs after which `bus_ok` turns false."""
SILENT_AFTER = 3
"""Consecutive BULK_READ timeouts at the same servo before it is pinged (a loaded machine can make
one reply late; a silent servo costs one reply timeout per tick until then)."""


class BusDown(BusError):
    pass


@dataclass
class TickStats:
    periods: deque[float] = field(default_factory=lambda: deque(maxlen=5000))
    walking_periods: deque[float] = field(default_factory=lambda: deque(maxlen=5000))
    work: deque[float] = field(default_factory=lambda: deque(maxlen=5000))
    goal_to_write: deque[float] = field(default_factory=lambda: deque(maxlen=500))
    ticks: int = 0
    overruns: int = 0
    early_ticks: int = 0

    def summary(self) -> dict[str, Any]:
        def pct(values: deque[float], q: float) -> float | None:
            if not values:
                return None
            data = sorted(values)
            return round(data[min(len(data) - 1, int(q * len(data)))] * 1000, 3)

        return {
            "ticks": self.ticks,
            "overruns": self.overruns,
            "early_ticks": self.early_ticks,
            "period_ms_p50": pct(self.periods, 0.50),
            "period_ms_p99": pct(self.periods, 0.99),
            "period_ms_max": pct(self.periods, 1.0),
            "period_ms_stdev": round(statistics.pstdev(self.periods) * 1000, 3)
            if len(self.periods) > 1
            else None,
            "walking_period_ms_p50": pct(self.walking_periods, 0.50),
            "walking_period_ms_p99": pct(self.walking_periods, 0.99),
            "walking_period_ms_max": pct(self.walking_periods, 1.0),
            "walking_periods": len(self.walking_periods),
            "work_ms_p50": pct(self.work, 0.50),
            "work_ms_p99": pct(self.work, 0.99),
            "goal_to_write_ms_p50": pct(self.goal_to_write, 0.50),
            "goal_to_write_ms_p99": pct(self.goal_to_write, 0.99),
            "goals_written": len(self.goal_to_write),
        }


class ControlLoop:
    def __init__(
        self,
        settings: MotionSettings,
        *,
        log: Any,
        port: Callable[[], str],
        publish: Callable[[Snapshot, bool], None],
        health: Callable[..., None],
    ) -> None:
        self.settings = settings
        self.log = log
        self._port = port
        self._publish = publish
        self._health = health
        self.executor = MotionExecutor(
            GaitParams(stride=settings.stride_mm, dt=settings.period_s),
            stand_time=settings.stand_time_s,
            renew_timeout=settings.renew_timeout_s,
        )
        self.stats = TickStats()
        self.counters: dict[str, int] = {"not_executed": 0, "renewals": 0, "watchdog_stops": 0}
        self.bus_ok = False
        self.missing: dict[int, float] = {}
        self.present: dict[int, int] = {}
        """Last present positions read from the servos."""
        self._goals: queue.SimpleQueue[GoalRequest] = queue.SimpleQueue()
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._reasoner_lost = threading.Event()
        self.attempted = threading.Event()
        """Set once the first connection attempt has succeeded or failed (no state is known before)."""
        self._lock = threading.Lock()
        self._last_detail = 0.0
        self._reported_counters: dict[str, int] = {}
        self._bus_silent = False

    # ------------------------------------------------------------------ from other threads
    def submit(self, goal: GoalRequest) -> None:
        self._goals.put(goal)
        if not (goal.action == Action.WALK_FORWARD and goal.goal_id == self.executor.walk_id):
            self._wake.set()  # a renewal changes nothing on the bus: no early tick for it

    def reasoner_lost(self) -> None:
        self._reasoner_lost.set()
        self._wake.set()

    def stop(self) -> None:
        self._stopping.set()
        self._wake.set()

    def snapshot(self) -> tuple[Snapshot, bool]:
        with self._lock:
            return self.executor.snapshot(), self.bus_ok

    # ------------------------------------------------------------------ thread body
    def run(self) -> None:
        while not self._stopping.is_set():
            port = ""
            try:
                port = self._port()
                bus = Op2Bus(port, baud=self.settings.baud, latency_ms=self.settings.latency_ms)
                try:
                    self._connect(bus)
                    self._ticks(bus)
                finally:
                    bus.close()
            except PortMissing as exc:
                hint = (
                    "connect the robot, set HRI_MOTION_PORT to its serial device, "
                    "or set HRI_MOTION_SIM=1 to drive the simulated OP2 bus"
                )
                self._down(HealthStatus.DEGRADED, str(exc), device=port, hint=hint)
            except JointsMissing as exc:
                self._down(
                    HealthStatus.DEGRADED, str(exc), device=port, missing=[describe(i) for i in exc.missing]
                )
            except (BusDown, NoAnswer, PortLost) as exc:
                self._down(HealthStatus.FAILED, str(exc), device=port)
            except BusError as exc:
                self._down(HealthStatus.DEGRADED, str(exc), device=port)
            except Exception as exc:  # a bug must not leave the robot without a control loop
                self.log.exception("control loop error")
                self._down(HealthStatus.FAILED, f"control loop error: {exc!r}", device=port)
            self.attempted.set()
            self._idle(self.settings.retry_s)

    def _down(self, status: HealthStatus, error: str, **detail: Any) -> None:
        with self._lock:
            self.bus_ok = False
            if self.executor.posture != Posture.UNKNOWN or self.executor.motion is not None:
                self.executor.motion = None
                self.executor.posture = Posture.UNKNOWN
                self.executor.changed = True
        self.log.error("bus not usable, retrying", error=error, retry_in_s=self.settings.retry_s, **detail)
        self._health(status, error=error, bus_ok=False, **detail)
        self._publish_if_changed()

    def _idle(self, seconds: float) -> None:
        """Wait before reconnecting, still answering goals (none can run without the bus)."""
        deadline = time.monotonic() + seconds
        while not self._stopping.is_set():
            self._drain_goals(time.monotonic(), fault="bus not connected")
            self._publish_if_changed()
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return
            self._wake.wait(min(remaining, 0.1))
            self._wake.clear()

    def _connect(self, bus: Op2Bus) -> None:
        bus.open()
        bus.power_on()
        bus.check_joints()
        present = bus.read_positions()
        bus.set_torque(True)
        bus.set_bulk_ids(list(JOINT_IDS))
        # health first: whoever sees a state with `bus_ok` and then asks health finds it OK too (the state publisher
        # runs on its own timer and may send one at any moment after `bus_ok` is set)
        self._health(HealthStatus.OK, error=None, bus_ok=True, device=bus.port_name, missing=[])
        with self._lock:
            self.present = present
            self.missing.clear()
            self.executor.attach(present)
            self.bus_ok = True
        self.log.info("bus ready", port=bus.port_name, posture=self.executor.posture.value)
        self._bus_silent = False
        self.attempted.set()

    # ------------------------------------------------------------------ ticks
    def _ticks(self, bus: Op2Bus) -> None:
        period = self.settings.period_s
        next_t = time.monotonic()
        last_start: float | None = None
        early = False
        bad_reads = 0
        streak, streak_id = 0, None  # consecutive timeouts at the same servo
        fail_since: float | None = None
        while not self._stopping.is_set():
            start = time.monotonic()
            if last_start is not None and not early:
                self.stats.periods.append(start - last_start)
                if self.executor.walking:
                    self.stats.walking_periods.append(start - last_start)
            last_start = start
            self.stats.ticks += 1
            fault = self._fault()
            with self._lock:
                self._drain_goals(start, fault=fault)
                if self.executor.expire(start):
                    self.counters["watchdog_stops"] += 1
                    self.log.warning(
                        "walk goal not renewed in time: stopping", timeout_s=self.settings.renew_timeout_s
                    )
                if self._reasoner_lost.is_set():
                    self._reasoner_lost.clear()
                    if self.executor.stop_walking():
                        self.counters["watchdog_stops"] += 1
                        self.log.warning("reasoner gone: stopping the walk")
                pose = self.executor.tick()
            when = bus.write_goals(clamp_pose(pose), GAINS)
            with self._lock:
                goal = self.executor.goal
                if self.executor.awaiting_write and goal is not None:
                    self.stats.goal_to_write.append(when - goal.received)
                self.executor.written(when)
            self._publish_if_changed()  # before the read: the state with first_write goes out at once
            result = bus.bulk_read()
            if result.ok:
                bad_reads, fail_since, streak, self._bus_silent = 0, None, 0, False
                self.present.update(result.positions)
            else:
                bad_reads += 1
                fail_since = fail_since or start
                streak = streak + 1 if result.failed_id == streak_id and result.timeout else 1
                streak_id = result.failed_id if result.timeout else None
                if streak >= SILENT_AFTER:
                    self._diagnose(bus, result.failed_id, result.timeout, result.message)
                if time.monotonic() - fail_since > self.settings.bus_down_s:
                    raise BusDown(
                        f"no valid reply on {bus.port_name} for {self.settings.bus_down_s} s: {result.message}"
                    )
            self._retry_missing(bus, start)
            ok = not self.missing and bad_reads < BAD_READS_FOR_NOT_OK
            if ok != self.bus_ok:
                with self._lock:
                    self.bus_ok = ok
                    self.executor.changed = True
            self._publish_if_changed()
            self._update_detail(bus, start)
            self.stats.work.append(time.monotonic() - start)
            next_t += period
            now = time.monotonic()
            if next_t < now:
                self.stats.overruns += 1
                next_t = now
            early = self._wake.wait(next_t - now)
            if early:
                self._wake.clear()
                self.stats.early_ticks += 1
                next_t = time.monotonic()

    def _fault(self) -> str | None:
        if self.missing:
            return "not answering: " + ", ".join(describe(i) for i in sorted(self.missing))
        if not self.bus_ok:
            return "servo reads failing"
        return None

    def _drain_goals(self, now: float, *, fault: str | None) -> None:
        while True:
            try:
                goal = self._goals.get_nowait()
            except queue.Empty:
                return
            outcome, why = self.executor.submit(goal, now, fault=fault)
            if outcome == Outcome.RENEWED:
                self.counters["renewals"] += 1
                continue
            if outcome in (Outcome.NOT_EXECUTED, Outcome.IGNORED):
                self.counters["not_executed"] += 1
                self.log.warning(
                    "goal not executed",
                    action=goal.action.value,
                    goal_id=goal.goal_id,
                    posture=self.executor.posture.value,
                    reason=why,
                    outcome=outcome.value,
                )
            else:
                self.log.info(
                    "goal",
                    action=goal.action.value,
                    goal_id=goal.goal_id,
                    outcome=outcome.value,
                    detail=why,
                    posture=self.executor.posture.value,
                )

    def _diagnose(self, bus: Op2Bus, failed_id: int | None, timeout: bool, message: str) -> None:
        """A BULK_READ failed at `failed_id`: a servo that no longer answers a ping is dropped."""
        if not timeout or failed_id is None:
            self.log.debug("bulk read error", failed_id=failed_id, error=message)
            return
        if self._bus_silent:
            return  # already known: nothing answers (BusDown after bus_down_s)
        if bus.ping(failed_id, retries=2) is not None:
            return
        if bus.ping(CM740_ID, retries=0) is None:
            self._bus_silent = True  # the whole bus, not one servo
            return
        with self._lock:
            self.missing[failed_id] = time.monotonic()
            if self.executor.stop_walking():
                self.counters["watchdog_stops"] += 1
            self.executor.changed = True
        bus.set_bulk_ids([j for j in JOINT_IDS if j not in self.missing])
        error = f"{describe(failed_id)} stopped answering on {bus.port_name}"
        self.log.error("servo lost", servo=describe(failed_id), port=bus.port_name)
        self._health(
            HealthStatus.DEGRADED,
            error=error,
            bus_ok=False,
            missing=[describe(i) for i in sorted(self.missing)],
        )

    def _retry_missing(self, bus: Op2Bus, now: float) -> None:
        if not self.missing or self.executor.walking:
            return
        for jid, since in list(self.missing.items()):
            if now - since < self.settings.retry_s:
                continue
            if bus.ping(jid, retries=0) is None:
                self.missing[jid] = now
                continue
            bus.set_torque(True, (jid,))
            del self.missing[jid]
            bus.set_bulk_ids([j for j in JOINT_IDS if j not in self.missing])
            self.log.info("servo back", servo=describe(jid))
        if not self.missing:
            self._health(HealthStatus.OK, error=None, bus_ok=True, missing=[])

    def _publish_if_changed(self) -> None:
        if not self.attempted.is_set():
            return
        with self._lock:
            if not self.executor.changed:
                return
            self.executor.changed = False
            snap, ok = self.executor.snapshot(), self.bus_ok
        self._publish(snap, ok)

    def _update_detail(self, bus: Op2Bus, now: float) -> None:
        """Health detail once a second, and at once when a goal counter changed."""
        if now - self._last_detail < 1.0 and self.counters == self._reported_counters:
            return
        self._last_detail = now
        self._reported_counters = dict(self.counters)
        self._health(None, bus=bus.counters.as_dict(), loop=self.stats.summary(), goals=dict(self.counters))
