"""Faults across real processes: killed services, a restarted reasoner, a vanished reasoner, garbage."""

from __future__ import annotations

import os
import signal
import time

from schemas import Action, Posture
from schemas.access import owners
from schemas.keys import SERVICES
from tests.system.conftest import Robot


def _kill(robot: Robot, name: str) -> int:
    pid = robot.launcher.pid(name)
    assert pid is not None
    os.kill(pid, signal.SIGKILL)
    return pid


def _wait_restarted(robot: Robot, name: str, old: int) -> None:
    assert robot.rec.wait(lambda: robot.launcher.pid(name) not in (None, old), timeout=20)
    # Health answers as soon as the session is up; the reasoner says `ready` once it also listens (waited for as True:
    # its health answers a moment before it first says `ready=False`)
    assert robot.rec.wait(lambda: (h := robot.health(name)) is not None and h.detail.get("pid") != old
                          and h.detail.get("ready", name != "reasoner") is True, timeout=30), f"{name} did not come back"
    time.sleep(0.5)  # the new subscriptions reach the router


def test_restarted_reasoner_still_refuses_go_after_an_x(robot: Robot) -> None:
    robot.play([
        {"say": "stand", "expect": {"posture": "standing"}},
        {"show": "X", "expect": {"situation": "danger"}},
        {"show": "none"},
    ])
    old = _kill(robot, "reasoner")
    _wait_restarted(robot, "reasoner", old)
    t0 = time.monotonic()
    robot.play([{"send": "go", "expect": {"verdict": "refuse", "reason": "danger_sign", "no_action": True}}])
    assert not [g for g in robot.rec.since(t0, "goal") if g.action is Action.WALK_FORWARD]
    assert robot.launcher.restarts("reasoner") == 1


def test_motion_stops_walking_when_the_reasoner_is_gone(robot: Robot) -> None:
    robot.play([{"send": "go", "expect": {"posture": "walking"}}])
    robot.launcher._restart = False  # the reasoner must stay dead for this test
    _kill(robot, "reasoner")
    t_kill = time.monotonic()
    stopped = robot.rec.wait(lambda: (s := robot.rec.latest_state) and s.posture is not Posture.WALKING and
                             s.action is None, timeout=10)
    assert stopped, "motion kept walking without a reasoner"
    assert time.monotonic() - t_kill < 3.0


def test_killing_each_service_never_lets_the_robot_walk_in_danger(robot: Robot) -> None:
    robot.play([
        {"say": "stand", "expect": {"posture": "standing"}},
        {"show": "X", "expect": {"situation": "danger"}},
        {"show": "none"},
    ])
    t0 = time.monotonic()
    for name in SERVICES:
        old = _kill(robot, name)
        # Ask to walk while the service is down and again once it is back.
        robot.play([{"send": "go", "timeout": 3}])
        _wait_restarted(robot, name, old)
        robot.play([{"send": "go", "expect": {"verdict": "refuse", "reason": "danger_sign"}}])
    assert not [g for g in robot.rec.since(t0, "goal") if g.action is Action.WALK_FORWARD]
    assert not robot.walking_states_since(t0)
    assert all(robot.launcher.restarts(n) == 1 for n in SERVICES)
    # And safety still releases: an O lets it walk again.
    robot.play([{"show": "O", "expect": {"situation": "safe"}}, {"send": "go", "expect": {"posture": "walking"}}])


GARBAGE = [b"not json", b"{}", b"[]", b"null", b'{"command": "fly"}', b"\x00\xff" * 64, b"{" * 10_000,
           b'{"marks": [{"shape": "X", "confidence": 7, "box": [0, 0, 1, 1]}]}']


def test_garbage_on_every_key_leaves_every_service_running(robot: Robot) -> None:
    k = robot.ctx.keys
    keys = [k.vision_marks, k.voice_command, k.reasoner_decision, k.motion_goal, k.motion_state, k.speech_say,
            k.speech_state, k.vision_scene]
    before = robot.pids()
    counted = ("vision", "reasoner", "motion", "speech")

    def all_rejected() -> bool:
        return all((h := robot.health(name)) is not None and h.rejected >= 1 for name in counted)

    # The access rules let only a key's owner put it: send each key's garbage as its owner.
    owner = {key: owners(key[len(k.prefix) + 1:])[0] for key in keys}
    sessions = {name: robot.session_as(name) for name in set(owner.values())}
    # Zenoh makes no promise for a put made before a subscription has propagated, so keep sending
    # until every service has counted a rejection (or give up and show each one's health).
    deadline = time.monotonic() + 15
    try:
        while True:
            for key in keys:
                for payload in GARBAGE:
                    sessions[owner[key]].put(key, payload)
            time.sleep(1.0)
            if all_rejected() or time.monotonic() > deadline:
                break
    finally:
        for session in sessions.values():
            session.close()
    assert robot.pids() == before
    for name in counted:
        h = robot.health(name)
        assert h is not None and h.rejected >= 1, (name, h)
    # Still working afterwards.
    robot.play([{"say": "stand", "expect": {"verdict": "obey", "posture": "standing"}}])
