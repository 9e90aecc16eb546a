"""Motion service benchmark: control-loop period jitter, goal-to-first-SYNC_WRITE latency, CPU use.

Starts a Zenoh router and `python -m services.motion` on the simulated OP2 bus (a child process of
the service), then:
1. idle (sitting) for --idle seconds: CPU% of service + simulator;
2. --goals head gestures (nod/shake alternately, each a new goal, sent at a random phase of the
   tick): latency from the goal's stamp
   (set just before publishing) to MotionState.first_write (the UNIX time of the first SYNC_WRITE that
   carried it), and the service's own received-to-write figure;
3. stand up, walk for --walk seconds with renewals every 0.5 s: CPU% while walking;
4. the 8 ms tick period p50/p99/max overall and while walking, from the service's health detail.

Prints one JSON object. Numbers are noisy on a loaded machine: the process competes for 2 cores.
"""

from __future__ import annotations

import json
import os
import random
import statistics
import threading
import time
import uuid
from pathlib import Path
from typing import Annotated, Any

import typer
import zenoh

from schemas.messages import Action, Health, MotionGoal, MotionState, Posture
from services.cli.rig import service_rig
from services.runtime import ServiceContext

TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int, *, children: bool = True) -> float:
    """utime + stime of a process and (by default) its child processes (the simulator), seconds."""
    total = 0.0
    pids = [pid]
    for task in Path(f"/proc/{pid}/task").glob("*") if children else ():  # children of any thread
        try:
            pids += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    for p in pids:
        try:
            fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
            total += (int(fields[11]) + int(fields[12])) / TICK
        except (OSError, IndexError):
            pass
    return total


def measure_cpu(pid: int, seconds: float, during: Any = None) -> dict[str, float]:
    """CPU% of one core used by the service and by its simulator child over `seconds`."""
    c0, s0, t0 = cpu_seconds(pid), cpu_seconds_children(pid), time.monotonic()
    if during is not None:
        during(seconds)
    else:
        time.sleep(seconds)
    span = time.monotonic() - t0
    total = 100.0 * (cpu_seconds(pid) - c0) / span
    sim = 100.0 * (cpu_seconds_children(pid) - s0) / span
    return {"service_plus_simulator": round(total, 1), "simulator": round(sim, 1)}


def cpu_seconds_children(pid: int) -> float:
    return cpu_seconds(pid) - cpu_seconds(pid, children=False)


def pct(values: list[float], q: float) -> float:
    data = sorted(values)
    return round(data[min(len(data) - 1, int(q * len(data)))], 3)


class Bench:
    def __init__(self, ctx: ServiceContext) -> None:
        self.ctx = ctx
        self.states: list[MotionState] = []
        self.cv = threading.Condition()
        ctx.subscribe(ctx.keys.motion_state, MotionState, self._on_state)
        self.goals = ctx.publisher(
            ctx.keys.motion_goal, MotionGoal, block=True, priority=zenoh.Priority.REAL_TIME
        )

    def _on_state(self, msg: MotionState) -> None:
        with self.cv:
            self.states.append(msg)
            self.cv.notify_all()

    def wait(self, pred: Any, timeout: float) -> MotionState:
        deadline = time.monotonic() + timeout
        with self.cv:
            while True:
                if self.states and pred(self.states[-1]):
                    return self.states[-1]
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError("motion state not reached")
                self.cv.wait(left)

    def send(self, action: Action, goal_id: str) -> MotionGoal:
        return self.goals.put(MotionGoal(action=action, goal_id=goal_id, stamp=time.time()))

    def health(self) -> Health:
        health = self.ctx.query_health("motion", timeout=3.0)
        if health is None:
            raise TimeoutError("no health reply")
        return health


def main(
    idle: Annotated[float, typer.Option(help="Seconds idle")] = 5.0,
    walk: Annotated[float, typer.Option(help="Seconds walking")] = 10.0,
    goals: Annotated[int, typer.Option(help="Head-gesture goals for the latency figure")] = 40,
) -> None:
    robot = f"bench{uuid.uuid4().hex[:6]}"
    result: dict[str, Any] = {"machine": {"cores": os.cpu_count(), "loadavg": os.getloadavg()}}
    with service_rig(robot, HRI_MOTION_SIM="1", HRI_LOG_LEVEL="warning") as rig:
        service = rig.start("motion", output=None)
        bench = Bench(rig.ctx)
        bench.wait(lambda s: s.posture == Posture.SITTING and s.bus_ok, 30)
        time.sleep(1.0)
        result["cpu_percent_idle"] = measure_cpu(service.pid, idle)

        latencies: list[float] = []
        for i in range(goals):
            goal = bench.send(Action.NOD if i % 2 == 0 else Action.SHAKE_HEAD, f"g{i}")
            state = bench.wait(lambda s, gid=f"g{i}": s.goal_id == gid and s.first_write is not None, 3)
            latencies.append((state.first_write - goal.stamp) * 1000)  # type: ignore[operator]
            time.sleep(0.15 + random.uniform(0.0, 0.008))  # random phase against the 8 ms tick
        result["goal_stamp_to_first_sync_write_ms"] = {
            "n": len(latencies),
            "p50": pct(latencies, 0.5),
            "p99": pct(latencies, 0.99),
            "max": round(max(latencies), 3),
            "mean": round(statistics.mean(latencies), 3),
        }
        time.sleep(1.1)  # the loop refreshes its health detail once a second
        loop = bench.health().detail["loop"]
        result["received_to_first_sync_write_ms"] = {
            "p50": loop["goal_to_write_ms_p50"],
            "p99": loop["goal_to_write_ms_p99"],
            "n": loop["goals_written"],
        }
        bench.wait(lambda s: s.action is None, 3)
        bench.send(Action.STAND_UP, "up")
        bench.wait(lambda s: s.posture == Posture.STANDING and s.action is None, 5)
        bench.send(Action.WALK_FORWARD, "walk")
        bench.wait(lambda s: s.posture == Posture.WALKING, 2)

        def keep_walking(seconds: float) -> None:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                time.sleep(0.5)
                bench.send(Action.WALK_FORWARD, "walk")

        result["cpu_percent_walking"] = measure_cpu(service.pid, walk, keep_walking)
        bench.send(Action.STOP, "halt")
        bench.wait(lambda s: s.posture == Posture.STANDING and s.action is None, 3)
        time.sleep(1.1)
        h = bench.health()
        loop = h.detail["loop"]
        result["tick_period_ms"] = {
            "all": {k: loop[f"period_ms_{k}"] for k in ("p50", "p99", "max", "stdev")},
            "walking": {k: loop[f"walking_period_ms_{k}"] for k in ("p50", "p99", "max")},
            "ticks": loop["ticks"],
            "overruns": loop["overruns"],
            "early_ticks_for_new_goals": loop["early_ticks"],
        }
        result["tick_work_ms"] = {"p50": loop["work_ms_p50"], "p99": loop["work_ms_p99"]}
        result["bus"] = h.detail["bus"]
        print(json.dumps(result, indent=2))


if __name__ == "__main__":
    typer.run(main)
