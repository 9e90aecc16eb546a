"""Watches the robot's traffic: keeps a timeline of what was heard, seen, decided, moved and said."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel

from schemas.messages import (
    Command,
    Decision,
    MarkObservation,
    MotionGoal,
    MotionState,
    Reason,
    SpeechRequest,
    SpeechState,
    VoiceCommand,
)
from services.runtime import ServiceContext

SENT_ENGINE = "scenario-send"
"""`VoiceCommand.engine` of commands a scenario publishes directly (no recogniser involved)."""


@dataclass(frozen=True)
class Event:
    t: float  # monotonic time of receipt
    kind: str  # heard, seen, decision, goal, motion, say, speaking
    msg: Any


def describe(event: Event) -> tuple[str, str]:
    """(source, human-readable text) of an event, for the timeline."""
    m = event.msg
    match event.kind:
        case "heard":
            what = m.command.value if m.command else "(nothing)"
            if m.engine == SENT_ENGINE:
                return "voice", f"sent {what}  (published directly: the recogniser was bypassed)"
            return "voice", f'heard "{m.text}" -> {what}  confidence {m.confidence:.4f}  [{m.engine}]'
        case "seen":
            shapes = ", ".join(f"{k.shape.value} {k.confidence:.2f}" for k in m.marks) or "no mark"
            return "vision", f"sees {shapes}  (frame {m.frame})"
        case "decision":
            cmd = m.command.value if m.command else ("(speech)" if m.reason is Reason.NOT_UNDERSTOOD else "(mark)")
            act = m.action.value if m.action else "no motion"
            line = (f"{m.verdict.value.upper():<6} {cmd:<6} reason={m.reason.value}  -> {act}  "
                    f"situation={m.situation.value}")
            if m.command is Command.WHY and m.say:  # the answer, recalled from episodic memory
                line += f'  answers "{m.say}"'
            return "reasoner", line
        case "goal":
            return "reasoner", f"goal {m.action.value}  ({m.goal_id})"
        case "motion":
            act = f"  doing {m.action.value}" if m.action else ""
            return "motion", f"posture {m.posture.value}{act}{'' if m.bus_ok else '  BUS FAULT'}"
        case "say":
            return "reasoner", f'asks to say "{m.text}"'
        case "speaking":
            if m.id is None:
                return "speech", "ready (not speaking)"
            return "speech", ("speaking" if m.speaking else "done") + f' "{m.text}"'
    return event.kind, str(m)


class Recorder:
    """Subscribes to every key of one robot and records events; `on_event` sees each as it comes."""

    def __init__(self, ctx: ServiceContext, on_event: Callable[[Event], None] | None = None) -> None:
        self.ctx = ctx
        self.events: list[Event] = []
        self._cond = threading.Condition()
        self._on_event = on_event
        self._last_shapes: tuple[str, ...] | None = None
        self._last_motion: tuple[Any, ...] | None = None
        self.latest_marks: MarkObservation | None = None
        self.latest_state: MotionState | None = None
        self.latest_speech: SpeechState | None = None
        self.goal_ids: set[str] = set()
        k = ctx.keys
        ctx.subscribe(k.voice_command, VoiceCommand, lambda m: self._add("heard", m))
        ctx.subscribe(k.vision_marks, MarkObservation, self._on_marks)
        ctx.subscribe(k.reasoner_decision, Decision, lambda m: self._add("decision", m))
        ctx.subscribe(k.motion_goal, MotionGoal, self._on_goal)
        ctx.subscribe(k.motion_state, MotionState, self._on_state)
        ctx.subscribe(k.speech_say, SpeechRequest, lambda m: self._add("say", m))
        ctx.subscribe(k.speech_state, SpeechState, self._on_speech)

    def _on_marks(self, m: MarkObservation) -> None:
        shapes = tuple(sorted(k.shape.value for k in m.marks))
        with self._cond:
            self.latest_marks = m
            changed = shapes != self._last_shapes
            self._last_shapes = shapes
            self._cond.notify_all()
        if changed:
            self._add("seen", m)

    def _on_goal(self, m: MotionGoal) -> None:
        with self._cond:
            renewal = m.goal_id in self.goal_ids
            self.goal_ids.add(m.goal_id)
        if not renewal:  # the reasoner renews a walk goal as a keep-alive; show each goal once
            self._add("goal", m)

    def _on_state(self, m: MotionState) -> None:
        sig = (m.posture, m.action, m.bus_ok)
        with self._cond:
            self.latest_state = m
            changed = sig != self._last_motion
            self._last_motion = sig
            self._cond.notify_all()
        if changed:
            self._add("motion", m)

    def _on_speech(self, m: SpeechState) -> None:
        with self._cond:
            self.latest_speech = m
        self._add("speaking", m)

    def _add(self, kind: str, msg: BaseModel) -> None:
        event = Event(time.monotonic(), kind, msg)
        with self._cond:
            self.events.append(event)
            self._cond.notify_all()
        if self._on_event:
            self._on_event(event)

    # ------------------------------------------------------------------ queries
    def since(self, t: float, kind: str) -> list[Any]:
        with self._cond:
            return [e.msg for e in self.events if e.t >= t and e.kind == kind]

    def wait(self, predicate: Callable[[], Any], timeout: float) -> Any:
        """Block until `predicate()` is truthy (re-checked on every event) or `timeout` passes."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                value = predicate()
                if value:
                    return value
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(min(left, 0.1))
