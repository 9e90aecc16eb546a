"""The whole robot with authentication and access control on (the default): strangers cannot join,
identities without the right cannot make it move, and the observer sees everything."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zenoh

from schemas import Action, MotionGoal, Posture, VoiceCommand
from schemas.access import RATE_LIMITS
from schemas.keys import SERVICES
from services.runtime import Credentials, client_config, encode
from tests.conftest import ROOT, read_lines
from tests.system.conftest import Robot

pytestmark = pytest.mark.system


def hri_env(robot: Robot, identity: str) -> dict[str, str]:
    env = {**os.environ, "HRI_ROBOT": robot.ctx.robot, "HRI_CREDENTIALS": str(robot.out / "keys" / identity)}
    env.pop("ZENOH_CONFIG", None)
    return env


def test_strangers_and_identities_without_the_right_cannot_move_the_robot(robot: Robot) -> None:
    endpoint = robot.launcher.endpoint
    with pytest.raises(zenoh.ZError):
        zenoh.open(client_config([endpoint])).close()  # no credentials: no session at all

    k = robot.ctx.keys
    t0 = time.monotonic()
    # Authenticated, but none of these may put a motion goal or a voice command.
    rogues = {name: robot.session_as(name) for name in ("observer", "vision", "speech", "motion")}
    try:
        for name, session in rogues.items():
            goal = session.declare_publisher(k.motion_goal)
            command = session.declare_publisher(k.voice_command)
            for i in range(5):
                goal.put(
                    encode(
                        MotionGoal(
                            action=Action.WALK_FORWARD, goal_id=f"{name}-{i}", stamp=time.time(), seq=i
                        )
                    )
                )
                command.put(
                    encode(
                        VoiceCommand(
                            command="go", text="go", confidence=1.0, engine=name, stamp=time.time(), seq=i
                        )
                    )
                )
                time.sleep(0.05)
        time.sleep(2.5)
    finally:
        for session in rogues.values():
            session.close()
    assert robot.rec.since(t0, "goal") == [] and robot.rec.since(t0, "heard") == []
    assert robot.rec.since(t0, "motion") == []  # the recorder logs posture changes: there were none
    latest = robot.rec.latest_state
    assert latest is not None and latest.posture is Posture.SITTING and latest.stamp > time.time() - 1.0
    motion = robot.health("motion")
    assert motion is not None and motion.rejected == 0  # nothing even reached it to be rejected
    # The operator may (this deployment grants it): the same "go" makes the robot walk.
    robot.play(
        [
            {"send": "go", "expect": {"verdict": "obey", "posture": "walking"}},
            {"send": "stop", "expect": {"posture": "standing"}},
        ]
    )


def test_status_and_spy_work_as_the_observer(robot: Robot) -> None:
    endpoint = robot.launcher.endpoint
    env = hri_env(robot, "observer")
    out = subprocess.run(
        [sys.executable, "-m", "services.cli", "status", "--json", "--connect", endpoint],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    rows = json.loads(out.stdout)
    assert all(rows[name]["alive"] and rows[name]["health"]["status"] for name in SERVICES)

    spy = subprocess.Popen(
        [sys.executable, "-m", "services.cli", "spy", "--connect", endpoint],
        cwd=ROOT,
        env={**env, "COLUMNS": "200"},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    lines, reader = read_lines(spy)
    try:
        # The spy has subscribed once it reports a liveliness token (it asks for their history after subscribing): a
        # fixed wait was not always enough for a process starting on a busy machine, and the decision came first.
        early = [lines.get(timeout=30)]
        while "+ alive" not in early[-1]:
            early.append(lines.get(timeout=30))
        robot.play([{"send": "yes", "expect": {"verdict": "obey"}}])
        time.sleep(0.5)
    finally:
        spy.send_signal(signal.SIGINT)
        spy.wait(timeout=15)
    reader.join(5)
    seen = "".join(early) + "".join(lines.queue)
    assert "motion/state" in seen and "reasoner/decision" in seen, seen[-2000:]

    # The observer may not send: `hri send` as the observer is dropped by the router.
    t0 = time.monotonic()
    subprocess.run(
        [sys.executable, "-m", "services.cli", "send", "command", "go", "--connect", endpoint],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    time.sleep(1.0)
    assert robot.rec.since(t0, "heard") == [] and robot.rec.since(t0, "goal") == []


def _flood(endpoint: str, creds: str, key: str, payload: bytes, seconds: float, rate: float) -> None:
    """Another process, authenticated as an identity allowed to put `key`, floods it."""
    session = zenoh.open(client_config([endpoint], Credentials.load(Path(creds))))
    try:
        pub = session.declare_publisher(key)
        t0 = time.perf_counter()
        sent = 0
        while (now := time.perf_counter()) - t0 < seconds:
            while sent < (now - t0) * rate:
                pub.put(payload)
                sent += 1
            time.sleep(0.001)
    finally:
        session.close()


def rss_mib(pid: int) -> float:
    line = next(x for x in Path(f"/proc/{pid}/status").read_text().splitlines() if x.startswith("VmRSS:"))
    return int(line.split()[1]) / 1024


def test_a_flooding_voice_cannot_stop_the_robot_from_stopping(robot: Robot) -> None:
    """`voice` may put commands; flooding them (about 50,000/s asked) must not delay an X's stop
    behind the flood nor grow the reasoner's memory. The router lets one session put at most
    `RATE_LIMITS` commands a second and drops the rest on arrival, so what reaches the reasoner and
    this test's recorder is cut 50-fold. (The reasoner's own bounded queue, for routers without the
    limits, is tested in tests/platform; the latency under flood is measured by
    bench/security_bench.py.)"""
    robot.play([{"send": "go", "expect": {"verdict": "obey", "posture": "walking"}}])
    reasoner = robot.launcher.pid("reasoner")
    assert reasoner is not None
    before = rss_mib(reasoner)
    payload = encode(VoiceCommand(command="go", text="go", confidence=1.0, engine="flood", stamp=1.0))
    flood = mp.get_context("spawn").Process(
        target=_flood,
        args=(
            robot.launcher.endpoint,
            str(robot.out / "keys" / "voice"),
            robot.ctx.keys.voice_command,
            payload,
            6.0,
            50_000.0,
        ),
    )
    flood_start = time.monotonic()
    flood.start()
    try:
        time.sleep(2.0)  # the flood is in full swing
        t0 = time.monotonic()
        robot.play(
            [{"show": "X", "expect": {"situation": "danger", "action": "stop", "posture": "standing"}}]
        )
        stop = next(g for g in robot.rec.since(t0, "goal") if g.action is Action.STOP)
        assert stop is not None
    finally:
        flood.join(30)
    # What got through the router: some, and at most the session's rate over the flood's life.
    flooded = [h for h in robot.rec.since(flood_start, "heard") if h.engine == "flood"]
    window = time.monotonic() - flood_start
    assert 0 < len(flooded) <= RATE_LIMITS["voice/command"] * window + 10, (len(flooded), window)
    assert rss_mib(reasoner) - before < 25, (before, rss_mib(reasoner))
    assert robot.launcher.pid("reasoner") == reasoner  # it never went down
