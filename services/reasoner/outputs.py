"""Turns the agent's outputs into messages on the bus, in the order the agent gave them:
motion goal first, then persistence, then speech, then the decision. So a Decision that
reports danger is only published once that danger is on disk.

An explanation (the answer to "why") becomes a speech request and the Decision for "why" (obey,
ok, no action, `say` the sentence); a `reasoner/explain` query waiting for it gets the
`Explanation`.

A sustained motion goal (walking) is re-published with the same goal_id every
`keepalive_s` until the agent sends any other motion goal (the contract with motion).
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from schemas.messages import (
    Action,
    Command,
    Decision,
    Explanation,
    HealthStatus,
    MotionGoal,
    Reason,
    Situation,
    SpeechRequest,
    Verdict,
)
from services.reasoner.agent_host import (
    DecisionOutput,
    ExplanationOutput,
    Memory,
    MotionOutput,
    Output,
    ReadyOutput,
    RememberOutput,
    SayOutput,
)
from services.reasoner.explain import explanation_model, render
from services.reasoner.state import StateStore
from services.runtime import ServiceContext, TypedPublisher


class OutputBridge:
    def __init__(
        self,
        ctx: ServiceContext,
        goals: TypedPublisher[MotionGoal],
        speech: TypedPublisher[SpeechRequest],
        decisions: TypedPublisher[Decision],
        store: StateStore,
        *,
        keepalive_s: float = 0.5,
    ) -> None:
        self._ctx = ctx
        self._goals = goals
        self._speech = speech
        self._decisions = decisions
        self._store = store
        self.keepalive_s = keepalive_s
        self._boot = uuid.uuid4().hex[:8]
        self._n = 0
        self._motion_lock = threading.Lock()  # a renewal never overtakes a newer goal
        self._sustained: MotionGoal | None = None
        self.situation: str | None = None
        self._waiting: dict[int, Future[Explanation]] = {}  # input id of a "why" -> its asker
        self._waiting_lock = threading.Lock()
        self.decisions = 0
        self.renewals = 0
        self.withheld = 0

    def _next_id(self, kind: str) -> str:
        self._n += 1
        return f"{self._boot}-{kind}{self._n}"

    def __call__(self, out: Output) -> None:
        """The agent's output sink (called on the Soar thread, in output order)."""
        if isinstance(out, MotionOutput):
            self._motion(out)
        elif isinstance(out, RememberOutput):
            self._remember(out.memory)
        elif isinstance(out, SayOutput):
            self._speech.put(SpeechRequest(text=out.text, id=self._next_id("say")))
        elif isinstance(out, DecisionOutput):
            self._decision(out)
        elif isinstance(out, ExplanationOutput):
            self._explanation(out)
        elif isinstance(out, ReadyOutput):
            self.situation = out.memory.situation

    def expect_explanation(self, cause: int) -> Future[Explanation]:
        """A future for the explanation the agent gives for the "why" with this input id."""
        future: Future[Explanation] = Future()
        with self._waiting_lock:
            self._waiting[cause] = future
        return future

    def forget_explanation(self, cause: int) -> None:
        with self._waiting_lock:
            self._waiting.pop(cause, None)

    def _explanation(self, out: ExplanationOutput) -> None:
        now = time.time()
        text = render(out, now)
        explanation = explanation_model(out, text, now)
        self._speech.put(SpeechRequest(text=text, id=self._next_id("say")))
        self._decision(DecisionOutput(command=Command.WHY.value, verdict=Verdict.OBEY.value,
                                      reason=Reason.OK.value, action=None, situation=out.situation, say=text,
                                      cause_stamp=out.cause_stamp))
        self._ctx.log.info("explanation", template=out.template, episode=out.episode, text=text)
        # A "why" that came while an earlier one was being answered replaces it in the agent
        # (65_explain.soar): one answer for the burst, given to every asker of it.
        with self._waiting_lock:
            answered = [c for c in self._waiting if out.cause is not None and c <= out.cause]
            futures = [self._waiting.pop(c) for c in answered]
        for future in futures:
            future.set_result(explanation)

    def _motion(self, out: MotionOutput) -> None:
        with self._motion_lock:
            goal = MotionGoal(
                action=Action(out.action), goal_id=self._next_id("goal"), cause_stamp=out.cause_stamp
            )
            self._goals.put(goal)
            self._sustained = goal if out.sustain else None
        self._ctx.log.info("motion goal", action=out.action, goal_id=goal.goal_id, sustained=out.sustain)

    def _remember(self, memory: Memory) -> None:
        try:
            self._store.save(memory)
        except OSError as exc:
            self._ctx.set_status(
                HealthStatus.DEGRADED, state_error=f"cannot save state in {self._store.directory}: {exc}"
            )
            self._ctx.log.error("state not saved", path=str(self._store.path), error=str(exc))

    def _decision(self, out: DecisionOutput) -> None:
        # A value outside the contract raises here: logged by the agent host, never published.
        decision = Decision(
            command=Command(out.command) if out.command else None,
            verdict=Verdict(out.verdict),
            reason=Reason(out.reason),
            action=Action(out.action) if out.action else None,
            situation=Situation(out.situation),
            say=out.say,
            cause_stamp=out.cause_stamp,
        )
        self.situation = out.situation
        self.decisions += 1
        self._decisions.put(decision)
        self._ctx.log.info("decision", command=out.command, verdict=out.verdict, reason=out.reason,
                           action=out.action, situation=out.situation)

    def renew(self, responsive: bool = True) -> bool:
        """Re-publish the sustained goal, if any (same goal_id, fresh stamp). An agent that is not
        responsive could not stop the walk for a danger: then the renewals stop, and the motion
        service stops the robot by itself (contract: no renewal within 2 s)."""
        with self._motion_lock:
            goal = self._sustained
            if goal is None:
                return False
            if not responsive:
                self.withheld += 1
                self._ctx.log.warning("agent not responsive: walk goal not renewed", goal_id=goal.goal_id)
                return False
            self._goals.put(goal.model_copy(update={"stamp": time.time()}))
        self.renewals += 1
        return True

    def run_keepalive(self, responsive: Callable[[], bool]) -> None:
        while not self._ctx.wait(self.keepalive_s):
            self.renew(responsive())

    def detail(self) -> dict[str, Any]:
        return {"situation": self.situation, "decisions": self.decisions, "walk_renewals": self.renewals,
                "walk_renewals_withheld": self.withheld,
                "walking_goal": self._sustained.goal_id if self._sustained is not None else None}
