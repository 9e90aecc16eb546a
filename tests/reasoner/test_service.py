"""The reasoner process over real Zenoh: JSON in, goals, speech and decisions out."""

from __future__ import annotations

import itertools
import json
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Generic, TypeVar, cast

import pytest
from pydantic import BaseModel

from schemas.messages import (
    Action,
    Command,
    Decision,
    Explanation,
    Health,
    Mark,
    MarkObservation,
    MotionGoal,
    MotionState,
    Posture,
    Shape,
    SpeechRequest,
    VoiceCommand,
)
from services.runtime import ServiceContext
from tests.conftest import ROOT, service_env, wait_for

M = TypeVar("M", bound=BaseModel)
REFUSAL = "Sorry, I cannot do it."


class Inbox(Generic[M]):
    """Every message of one model received on one key, in order."""

    def __init__(self, bus: ServiceContext, key: str, model: type[M]) -> None:
        self.items: list[M] = []
        self._lock = threading.Lock()
        bus.subscribe(key, model, self._add)

    def _add(self, msg: M) -> None:
        with self._lock:
            self.items.append(msg)

    def snapshot(self) -> list[M]:
        with self._lock:
            return list(self.items)

    def wait(self, pred: Callable[[M], bool], timeout: float = 5.0) -> M:
        return cast(M, wait_for(lambda: next((m for m in self.snapshot() if pred(m)), None), timeout))


def wait_ready(bus: ServiceContext, proc: subprocess.Popen[bytes], timeout: float = 20.0) -> Health:
    def ready() -> Health | None:
        assert proc.poll() is None, Path(proc.log_path).read_text()  # type: ignore[attr-defined]
        h = bus.query_health("reasoner", timeout=1.0)
        return h if h is not None and h.detail.get("ready") else None

    return wait_for(ready, timeout, interval=0.1)  # type: ignore[return-value]


def marks(*shapes: Shape) -> MarkObservation:
    return MarkObservation(marks=[Mark(shape=s, confidence=0.9, box=(10, 10, 50, 50)) for s in shapes])


@pytest.fixture
def io(bus: ServiceContext) -> dict[str, object]:
    k = bus.keys
    return {
        "goals": Inbox(bus, k.motion_goal, MotionGoal),
        "decisions": Inbox(bus, k.reasoner_decision, Decision),
        "speech": Inbox(bus, k.speech_say, SpeechRequest),
        "voice": bus.publisher(k.voice_command, VoiceCommand),
        "marks": bus.publisher(k.vision_marks, MarkObservation),
        "motion": bus.publisher(k.motion_state, MotionState),
    }


def test_walk_keepalive_danger_stop_and_refusal(bus: ServiceContext, start_service, io) -> None:  # type: ignore[no-untyped-def]
    goals, decisions, speech = io["goals"], io["decisions"], io["speech"]
    wait_ready(bus, start_service("reasoner"))
    io["motion"].put(MotionState(posture=Posture.STANDING))
    go = io["voice"].put(VoiceCommand(command=Command.GO, text="go", confidence=0.9))
    walk = goals.wait(lambda g: g.action == "walk_forward")
    assert walk.cause_stamp == pytest.approx(go.stamp)
    d = decisions.wait(lambda d: d.command == "go")
    assert (d.verdict, d.reason, d.action, d.situation) == ("obey", "ok", "walk_forward", "safe")
    # Keep-alive: the same goal_id again and again, about every 0.5 s.
    wait_for(lambda: len([g for g in goals.snapshot() if g.goal_id == walk.goal_id]) >= 3, 3.0)
    renewals = [g for g in goals.snapshot() if g.goal_id == walk.goal_id]
    gaps = [b.stamp - a.stamp for a, b in itertools.pairwise(renewals)]
    assert all(0.25 < gap < 0.95 for gap in gaps), gaps  # every 0.5 s, on a loaded machine

    io["motion"].put(MotionState(posture=Posture.WALKING, action=Action.WALK_FORWARD, goal_id=walk.goal_id))
    time.sleep(0.1)
    x = io["marks"].put(marks(Shape.X))
    stop = goals.wait(lambda g: g.action == "stop")
    assert stop.cause_stamp == pytest.approx(x.stamp) and stop.goal_id != walk.goal_id
    d = decisions.wait(lambda d: d.situation == "danger")
    assert (d.command, d.reason, d.action) == (None, "danger_sign", "stop")
    after_stop = len(goals.snapshot())
    time.sleep(1.0)  # no renewal of the walk after the stop
    assert [g.action for g in goals.snapshot()[after_stop:]] == []

    io["motion"].put(MotionState(posture=Posture.STANDING))
    io["voice"].put(VoiceCommand(command=Command.GO, text="go", confidence=0.95))
    d = decisions.wait(lambda d: d.verdict == "refuse")
    assert (d.command, d.reason, d.say) == ("go", "danger_sign", REFUSAL)
    assert speech.wait(lambda s: True).text == REFUSAL
    assert all(g.action != "walk_forward" for g in goals.snapshot()[after_stop:])


def test_danger_survives_sigkill(bus: ServiceContext, start_service, io, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    proc = start_service("reasoner")
    wait_ready(bus, proc)
    io["marks"].put(marks(Shape.TRIANGLE))
    io["decisions"].wait(lambda d: d.situation == "danger")
    state = json.loads((tmp_path / "state" / "reasoner.json").read_text())
    assert state["situation"] == "danger"
    proc.send_signal(signal.SIGKILL)
    proc.wait(10)

    wait_ready(bus, start_service("reasoner"))
    io["motion"].put(MotionState(posture=Posture.STANDING))
    io["voice"].put(VoiceCommand(command=Command.GO, text="go", confidence=0.9))
    d = io["decisions"].wait(lambda d: d.command == "go")
    assert (d.verdict, d.reason, d.situation) == ("refuse", "danger_sign", "danger")
    time.sleep(0.3)
    assert all(g.action != "walk_forward" for g in io["goals"].snapshot())


def _explain(bus: ServiceContext) -> Explanation:
    replies = list(bus.session.get(bus.keys.reasoner_explain, timeout=5.0))
    assert len(replies) == 1 and replies[0].ok is not None, replies
    return Explanation.model_validate_json(replies[0].ok.payload.to_bytes())


def test_why_after_sigkill_is_answered_from_the_episodes_on_disk(  # type: ignore[no-untyped-def]
    bus: ServiceContext, start_service, io, tmp_path: Path
) -> None:
    proc = start_service("reasoner")
    wait_ready(bus, proc)
    io["motion"].put(MotionState(posture=Posture.STANDING))
    io["marks"].put(marks(Shape.TRIANGLE))
    io["decisions"].wait(lambda d: d.situation == "danger")
    io["voice"].put(VoiceCommand(command=Command.GO, text="go", confidence=0.9))
    io["decisions"].wait(lambda d: d.command == "go")
    proc.send_signal(signal.SIGKILL)
    proc.wait(10)
    assert (tmp_path / "state" / "episodes.db").is_file()

    proc = start_service("reasoner")
    wait_ready(bus, proc)
    started = Path(proc.log_path).read_text()  # type: ignore[attr-defined]
    line = [li for li in started.splitlines() if "state restored from" in li][-1]  # this start's
    assert str(tmp_path / "state" / "reasoner.json") in line and "situation danger" in line and "2 episodes" in line
    # spoken "why": the Decision carries the sentence, the speech service gets it, no goal
    why = io["voice"].put(VoiceCommand(command=Command.WHY, text="why", confidence=0.9))
    d = io["decisions"].wait(lambda d: d.command == "why")
    assert (d.verdict, d.reason, d.action, d.situation) == ("obey", "ok", None, "danger")
    assert d.cause_stamp == pytest.approx(why.stamp)
    assert d.say is not None and d.say.startswith("I saw a triangle") and "Show me an O" in d.say
    assert io["speech"].wait(lambda s: s.text == d.say)
    # asked over the bus: the structured answer
    explanation = _explain(bus)
    assert explanation.text == d.say and explanation.reason == "danger_sign"
    assert explanation.decision is not None and explanation.decision.command == "go"
    assert [(e.kind, e.what) for e in explanation.evidence] == [("command", "go"), ("mark", "TRIANGLE")]
    assert explanation.episode == 2 and explanation.evidence[1].episode == 1
    assert all(g.action != "walk_forward" for g in io["goals"].snapshot())


def test_bad_payloads_and_unknown_speech(bus: ServiceContext, start_service, io) -> None:  # type: ignore[no-untyped-def]
    proc = start_service("reasoner")
    wait_ready(bus, proc)
    k = bus.keys
    for key in (k.voice_command, k.vision_marks, k.motion_state, k.speech_state):
        bus.session.put(key, b"{not json")
        bus.session.put(key, json.dumps({"command": "fly", "posture": 3, "marks": "X"}))
    io["voice"].put(VoiceCommand(command=None, text="table", confidence=0.7))
    d = io["decisions"].wait(lambda d: d.reason == "not_understood")
    assert (d.command, d.verdict) == (None, "ignore")
    assert io["speech"].wait(lambda s: True).text == "Sorry, I did not understand."
    assert proc.poll() is None
    h = cast(Health, wait_for(lambda: (h := bus.query_health("reasoner", timeout=1.0)) is not None and h.rejected >= 6 and h))
    assert h.status == "ok" and h.detail["callback_errors"] == 0


def _soar_cli(router_endpoint: str, robot_id: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "services.reasoner", "soar", *args],
        cwd=ROOT, env=service_env(router_endpoint, robot_id), capture_output=True, text=True, timeout=30,
    )


def test_soar_command_line_on_the_live_agent(
    bus: ServiceContext, start_service, router_endpoint: str, robot_id: str  # type: ignore[no-untyped-def]
) -> None:
    wait_ready(bus, start_service("reasoner"))
    done = _soar_cli(router_endpoint, robot_id, "print s1")
    assert done.returncode == 0, done.stderr
    assert "^situation safe" in done.stdout
    done = _soar_cli(router_endpoint, robot_id, "exit")
    assert done.returncode == 1 and "SIGTERM" in done.stderr
    done = _soar_cli(router_endpoint, robot_id, "no-such-soar-command")
    assert done.returncode == 1 and done.stderr.strip()


def test_soar_command_line_without_a_reasoner(router_endpoint: str) -> None:
    done = _soar_cli(router_endpoint, "nobody-home", "print s1", "--timeout", "1")
    assert done.returncode == 1
    assert "no reasoner answered" in done.stderr


def test_sigterm_stops_cleanly(bus: ServiceContext, start_service) -> None:  # type: ignore[no-untyped-def]
    proc = start_service("reasoner")
    wait_ready(bus, proc)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(10) == 0
    assert "stopped" in Path(proc.log_path).read_text()  # type: ignore[attr-defined]


def test_hri_why_without_a_reasoner(router_endpoint: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "services.cli.main", "why", "--timeout", "1"],
        cwd=ROOT, env=service_env(router_endpoint, "nobody-home"), capture_output=True, text=True, timeout=30,
    )
    assert done.returncode == 1
    assert "no reasoner answered on hri/nobody-home/reasoner/explain" in done.stderr
