"""The whole robot (five processes, real router): the confirmation dialogue of an unsure "go"
(issue #12) and "why" answered from the reasoner's episodic memory (issue #15), asked by voice
and with `hri why` over the bus."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import warnings

from schemas import Action
from schemas.messages import Command, Decision, Verdict, VoiceCommand
from tests.conftest import ROOT
from tests.system.conftest import Robot

ASK = "Shall I walk forward?"


def _hear(robot: Robot, command: Command, confidence: float) -> float:
    """Publish what the voice service would for a command heard with this confidence (and as it does:
    congestion blocks rather than drops)."""
    t0 = time.monotonic()
    robot.ctx.publisher(robot.ctx.keys.voice_command, VoiceCommand, block=True).put(
        VoiceCommand(command=command, text=command.value, confidence=confidence, engine="systest"))
    return t0


def _where(robot: Robot, t0: float) -> str:
    """Where a command may have been lost: on the way (received), in the queue (dropped) or in the agent."""
    health = robot.health("reasoner")
    seen = [m.command for m in robot.rec.since(t0, "heard")]
    where = (f"reasoner received {health.received}, rejected {health.rejected}, detail {health.detail}"
             if health else "the reasoner did not answer its health query")
    return f"the recorder heard {seen}; {where}; see {robot.log_path}"


def _decision(robot: Robot, t0: float, command: Command, timeout: float = 8.0) -> Decision | None:
    return robot.rec.wait(lambda: next((d for d in robot.rec.since(t0, "decision") if d.command is command), None),
                          timeout)


def _decided(robot: Robot, t0: float, command: Command) -> Decision:
    found = _decision(robot, t0, command)
    assert found is not None, f"no decision for {command.value} ({_where(robot, t0)})"
    return found


def _answer(robot: Robot, command: Command, confidence: float) -> tuple[float, Decision]:
    """Answer the robot's question; said again once, as a person would, if it went unanswered for 2 s.
    In 2 of 5 CI runs, and about 1 in 30 local ones, a "yes" sent 10 ms after the question was spoken got
    no decision at all, with no drop logged; a repeat is reported as a warning saying where it was lost,
    and the dialogue is still asserted on the answer the robot did hear (closing note, stop 37). Not seen
    since: no repeat in the CI-exact runs of stops 39-44 (six), nor in 70 local runs of this test at stop 44
    (half of them with a busy loop on one core; 30 with this publisher dropping under congestion again, as
    it did before the repeat was added), and the Soar agent alone answers a "yes" put in after any of 0-15
    decision cycles of the "go" it answers. The cause is still unknown; the repeat stays, and warns."""
    t = _hear(robot, command, confidence)
    found = _decision(robot, t, command, 2.0)
    if found is None:
        warnings.warn(f"no decision for the answer {command.value!r} in 2 s; said again ({_where(robot, t)})",
                      stacklevel=2)
        t = _hear(robot, command, confidence)
        found = _decided(robot, t, command)
    return t, found


def test_unsure_go_is_confirmed_or_times_out_and_why_explains(robot: Robot) -> None:
    robot.play([{"say": "stand", "expect": {"verdict": "obey", "posture": "standing"}}])

    # Asked, and nobody answers: after the dialogue's 5 s the question is dropped, no walk.
    t0 = _hear(robot, Command.GO, 0.6)
    ask = _decided(robot, t0, Command.GO)
    assert (ask.verdict, ask.reason, ask.action, ask.say) == (Verdict.ASK, "confirm", None, ASK)
    assert robot.rec.wait(lambda: [s for s in robot.rec.since(t0, "say") if s.text == ASK], 5)
    timed_out = robot.rec.wait(lambda: [d for d in robot.rec.since(t0, "decision")
                                        if d.command is Command.GO and d.verdict is Verdict.IGNORE], 9)
    assert timed_out and timed_out[0].reason == "confirm"
    assert not [g for g in robot.rec.since(t0, "goal") if g.action is Action.WALK_FORWARD]

    # Asked again, and a confident "yes": the robot walks, and does not nod.
    t1 = _hear(robot, Command.GO, 0.7)
    assert _decided(robot, t1, Command.GO).verdict is Verdict.ASK
    # a person answers a question once it has been asked aloud; answered the instant the decision
    # shows, the "yes" could reach the router within 1 ms of the "go" and be dropped by its input
    # rate limit (schemas.access.RATE_LIMITS), as a flood would be
    assert robot.rec.wait(lambda: [s for s in robot.rec.since(t1, "say") if s.text == ASK], 5)
    t2, yes = _answer(robot, Command.YES, 0.9)
    assert (yes.verdict, yes.action) == (Verdict.OBEY, Action.WALK_FORWARD)
    assert robot.rec.wait(lambda: robot.walking_states_since(t2), 5)
    # the walk goal itself is recorded before "why" is sent: on a loaded machine the recorder's
    # callback for the goal can run after the one for the motion state it caused, and the "why" step
    # would then count the walk as its own motion
    assert robot.rec.wait(lambda: [g for g in robot.rec.since(t2, "goal") if g.action is Action.WALK_FORWARD], 5)
    assert [g.action for g in robot.rec.since(t2, "goal")
            if g.action is not Action.WALK_FORWARD] == []  # no nod

    # "why", as a command on the bus: the answer is a Decision, spoken, and moves nothing.
    robot.play([{"send": "why", "expect": {"heard": "why", "verdict": "obey", "no_action": True,
                                           "said": "you said yes"}}])
    # `hri why` asks the same over the queryable and prints the structured answer.
    env_connect = robot.launcher.endpoint
    as_observer = {**os.environ, "HRI_KEYS_DIR": str(robot.out / "keys")}  # the deployment's identities
    as_observer.pop("HRI_CREDENTIALS", None)
    done = subprocess.run([sys.executable, "-m", "services.cli.main", "why", "--json", "--robot", robot.ctx.keys.robot,
                           "--connect", env_connect], cwd=ROOT, capture_output=True, text=True, timeout=60,
                          env=as_observer)
    assert done.returncode == 0, done.stderr
    answer = json.loads(done.stdout)
    assert answer["text"].startswith("I asked whether to walk, and you said yes")
    assert answer["decision"]["command"] == "yes" and answer["decision"]["action"] == "walk_forward"
    assert answer["episode"] >= 1 and [e["what"] for e in answer["evidence"]] == ["yes"]
    robot.play([{"say": "stop", "expect": {"verdict": "obey", "posture": "standing"}}])
