"""Reasoner benchmark: decision latency and sustained input rate, across processes over a real
Zenoh router (zenoh-python, loopback TCP).

    .venv/bin/python bench/reasoner_latency.py [--count 400] [--rates 1000,2000,3000,4000]

Three processes: a router, the reasoner (`python -m services.reasoner`), and this script,
which publishes VoiceCommand "yes"/"no" (each obeyed with a nod/shake goal and a Decision, the
motion state being "standing") and listens for the MotionGoals.

- latency: commands paced at 50 Hz. `bus->goal` is goal receipt minus command stamp (publish
  here, router, reasoner, Soar, publish, router, here); `in->out` is goal stamp minus command
  stamp (one hop in plus the reasoner's work), the closest to "input received to goal published".
- sustained rate: commands at a fixed rate for a few seconds each; a rate is sustained when
  decisions keep up (>= 97 %) and the lag after the last command stays under 0.5 s.
Figures on a shared 2-core machine are noisy; run it a few times.
"""

from __future__ import annotations

import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import typer

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from schemas.messages import Command, Decision, MotionGoal, MotionState, Posture, VoiceCommand  # noqa: E402
from services.cli.rig import service_rig  # noqa: E402
from services.runtime import ServiceContext  # noqa: E402


class Collector:
    def __init__(self, ctx: ServiceContext) -> None:
        self.goals: list[tuple[float, MotionGoal]] = []
        self.decisions = 0
        self.last_decision = 0.0
        self._lock = threading.Lock()
        ctx.subscribe(ctx.keys.motion_goal, MotionGoal, self._goal)
        ctx.subscribe(ctx.keys.reasoner_decision, Decision, self._decision)

    def _goal(self, goal: MotionGoal) -> None:
        now = time.time()
        with self._lock:
            self.goals.append((now, goal))

    def _decision(self, _d: Decision) -> None:
        with self._lock:
            self.decisions += 1
            self.last_decision = time.time()

    def reset(self) -> None:
        with self._lock:
            self.goals.clear()
            self.decisions = 0


def _pct(values: list[float], p: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(p / 100 * (len(ordered) - 1)))]


def _words(i: int) -> Command:
    return Command.YES if i % 2 else Command.NO


def measure_latency(ctx: ServiceContext, col: Collector, count: int) -> None:
    pub = ctx.publisher(ctx.keys.voice_command, VoiceCommand)
    col.reset()
    sent: dict[float, float] = {}
    for i in range(count):
        msg = pub.put(VoiceCommand(command=_words(i), text="", confidence=0.9))
        sent[msg.stamp] = msg.stamp
        time.sleep(0.02)
    time.sleep(0.5)
    e2e, in_out = [], []
    for received, goal in col.goals:
        if goal.cause_stamp in sent:
            e2e.append((received - goal.cause_stamp) * 1000)
            in_out.append((goal.stamp - goal.cause_stamp) * 1000)
    typer.echo(f"latency over {len(e2e)}/{count} commands (ms):")
    for name, values in (("bus->goal", e2e), ("in->out", in_out)):
        if values:
            typer.echo(f"  {name:10s} p50 {_pct(values, 50):6.2f}  p99 {_pct(values, 99):6.2f}  "
                       f"max {max(values):6.2f}  mean {statistics.fmean(values):6.2f}")


def measure_rate(ctx: ServiceContext, col: Collector, rate: int, seconds: float) -> tuple[float, float, int]:
    pub = ctx.publisher(ctx.keys.voice_command, VoiceCommand)
    col.reset()
    total = int(rate * seconds)
    start = time.monotonic()
    max_backlog = 0
    next_probe = start + 0.5
    for i in range(total):
        target = start + i / rate
        now = time.monotonic()
        if target > now:
            time.sleep(target - now)
        pub.put(VoiceCommand(command=_words(i), text="", confidence=0.9))
        if now >= next_probe:
            h = ctx.query_health("reasoner", timeout=1.0)
            if h is not None:
                max_backlog = max(max_backlog, int(h.detail.get("backlog", 0)))
            next_probe = now + 0.5
    sent_at = time.time()
    deadline = time.monotonic() + 10.0
    while col.decisions < total and time.monotonic() < deadline:
        time.sleep(0.01)
    lag = max(0.0, col.last_decision - sent_at) if col.decisions else float("inf")
    return col.decisions / total, lag, max_backlog


def main(
    count: int = typer.Option(400, help="Paced commands for the latency figure"),
    rates: str = typer.Option("1000,2000,3000,4000,5000", help="Input rates to try (messages/s)"),
    seconds: float = typer.Option(3.0, help="Seconds per rate"),
    log_level: str = typer.Option("warning", help="HRI_LOG_LEVEL of the reasoner under test"),
) -> None:
    """Print decision latency p50/p99 and the sustained input rate of the reasoner."""
    with tempfile.TemporaryDirectory() as state, \
            service_rig(f"bench{os.getpid()}", HRI_STATE_DIR=state, HRI_LOG_LEVEL=log_level,
                        HRI_REASONER_COMMAND_RATE="0") as rig:  # capacity, not the flood limit
        rig.start("reasoner")
        ctx = rig.ctx
        deadline = time.monotonic() + 30
        while not ((h := ctx.query_health("reasoner", timeout=1.0)) and h.detail.get("ready")):
            if time.monotonic() > deadline:
                raise RuntimeError("the reasoner did not become ready")
            time.sleep(0.1)
        col = Collector(ctx)
        ctx.publisher(ctx.keys.motion_state, MotionState).put(MotionState(posture=Posture.STANDING))
        time.sleep(0.3)
        typer.echo(f"reasoner bench, {os.cpu_count()} CPUs, reasoner log level {log_level}")
        measure_latency(ctx, col, count)
        typer.echo("sustained input rate (VoiceCommand -> Decision + MotionGoal):")
        best = 0
        for rate in (int(r) for r in rates.split(",") if r.strip()):
            ratio, lag, backlog = measure_rate(ctx, col, rate, seconds)
            ok = ratio >= 0.97 and lag < 0.5
            best = rate if ok else best
            typer.echo(f"  {rate:6d}/s: decided {ratio * 100:5.1f} %, "
                       f"lag after last {lag * 1000:7.1f} ms, "
                       f"max backlog {backlog:5d}  {'sustained' if ok else 'falls behind'}")
            if not ok:
                break
            time.sleep(1.0)
        typer.echo(f"highest sustained rate tried: {best}/s")


if __name__ == "__main__":
    typer.run(main)
