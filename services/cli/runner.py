"""Runs a scenario against a live robot (real processes, real Zenoh) and checks each step's outcome."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from schemas.keys import SERVICES
from schemas.messages import (
    Decision,
    Health,
    MotionGoal,
    MotionState,
    Posture,
    SceneCommand,
    Verdict,
    VoiceCommand,
)
from services.cli.probe import alive_services
from services.cli.recorder import SENT_ENGINE, Recorder
from services.cli.scenario import Scenario, Step
from services.cli.utterance import DEFAULT_VOICE, speak_into
from services.runtime import ServiceContext

SETTLE_S = 8.0  # longest a motion may take to finish before the next step
GAP_S = 0.3  # pause between steps, as a person would leave


@dataclass
class StepResult:
    index: int
    step: Step
    problems: list[str] = field(default_factory=list)
    heard: VoiceCommand | None = None
    decision: Decision | None = None
    asked: Decision | None = None
    """The robot's question, when it asked back and the step's `confirm` answered it (`decision` is the answer's)."""
    goals: list[MotionGoal] = field(default_factory=list)
    posture: Posture | None = None
    said: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.problems


class ScenarioRunner:
    def __init__(self, ctx: ServiceContext, recorder: Recorder, spool: Path, *, voice: str = DEFAULT_VOICE) -> None:
        self.ctx = ctx
        self.rec = recorder
        self.spool = spool
        self.voice = voice
        self._scene = ctx.publisher(ctx.keys.vision_scene, SceneCommand)
        self._voice = ctx.publisher(ctx.keys.voice_command, VoiceCommand, block=True)  # as the voice service

    # ------------------------------------------------------------------ readiness
    def wait_ready(self, timeout: float = 90.0) -> list[str]:
        """Wait for a working servo bus with a known posture, camera frames, vision listening for scene commands, all
        five services' liveliness tokens and a ready reasoner.

        A token is declared as its service's session opens, just before the service declares its subscribers, so it
        says the process is up, not yet that it listens. What makes that safe here: a word is a WAV in the voice
        service's spool folder, which the service reads from the start (a word spoken early is heard late, not lost);
        the reasoner's `ready` says it listens to every input; and the speech service is asked to speak only when the
        reasoner answers an input, which a scenario sends after all this.

        Returns what is still missing after `timeout` (empty when ready).
        """

        def bus_ready() -> bool:
            s = self.rec.latest_state
            return s is not None and s.bus_ok and s.posture != Posture.UNKNOWN

        deadline = time.monotonic() + timeout
        # Vision is the only subscriber of the scene key: until that subscription reaches this session
        # a `show` step would be dropped, even though marks already flow.
        self.rec.wait(lambda: bus_ready() and self.rec.latest_marks is not None and self._scene.matched, timeout)
        alive = alive_services(self.ctx.session, self.ctx.keys, timeout=1.0)
        while set(SERVICES) - alive and time.monotonic() < deadline:
            time.sleep(0.2)
            alive = alive_services(self.ctx.session, self.ctx.keys, timeout=1.0)
        reasoner_ready = False
        while not reasoner_ready and time.monotonic() < deadline:
            reasoner_ready = self._reasoner_ready()
            if not reasoner_ready:
                time.sleep(0.2)
        missing = []
        if not bus_ready():
            missing.append("motion state with a working servo bus")
        if self.rec.latest_marks is None:
            missing.append("vision frames")
        elif not self._scene.matched:
            missing.append("vision listening for scene commands")
        if absent := sorted(set(SERVICES) - alive):
            missing.append(f"{', '.join(absent)} on the bus")
        if not reasoner_ready:
            missing.append("a reasoner ready for input")
        return missing

    def speak(self, words: str) -> None:
        """Say `words` to the robot: a synthesised WAV into the voice service's spool folder."""
        speak_into(self.spool, words, voice=self.voice)

    def _reasoner_ready(self) -> bool:
        """The reasoner's health says `ready` once its agent is restored and it listens to every input."""
        health = self.health("reasoner", timeout=1.0)
        return health is not None and bool(health.detail.get("ready"))

    def health(self, service: str, timeout: float = 2.0) -> Health | None:
        """A service's answer on its health queryable (None: no answer, or not a valid `Health`)."""
        return self.ctx.query_health(service, timeout)

    def run(self, scenario: Scenario, on_step: Callable[[StepResult], None] | None = None) -> list[StepResult]:
        results = []
        for i, step in enumerate(scenario.steps, 1):
            result = self.run_step(i, step)
            results.append(result)
            if on_step:
                on_step(result)
        return results

    # ------------------------------------------------------------------ one step
    def run_step(self, index: int, step: Step) -> StepResult:
        res = StepResult(index, step)
        t0 = time.monotonic()
        known_goals = set(self.rec.goal_ids)
        exp = step.expect
        if step.say is not None or step.send is not None:
            if step.say is not None:
                self.speak(step.say)
            else:
                self._voice.put(VoiceCommand(command=step.send, text=step.send.value, confidence=1.0,
                                             engine=SENT_ENGINE))
            res.heard = self._first_heard(t0, step.timeout)
            if res.heard is None:
                res.problems.append("the voice service published nothing")
            else:
                res.decision = self.rec.wait(lambda: self._decision_for(t0, res.heard), step.timeout)
                if res.decision is not None and res.decision.verdict == Verdict.ASK and step.confirm is not None:
                    self._answer(res, step.confirm)
                if res.decision is None and exp is not None and (exp.verdict or exp.reason or exp.situation):
                    res.problems.append("the reasoner made no decision")
        elif step.show is not None:
            self._scene.put(SceneCommand(shape=step.shape))
            want = {step.shape.value} if step.shape else set()
            shown_at = time.time()

            def shows_it() -> bool:  # a frame taken after the card went up, with exactly these marks
                latest = self.rec.latest_marks
                return latest is not None and latest.stamp >= shown_at and {m.shape.value for m in latest.marks} == want

            seen = self.rec.wait(shows_it, step.timeout)
            if not seen:
                res.problems.append(f"vision never reported {sorted(want) or 'no mark'}")
            elif exp is not None and (exp.situation or exp.verdict or exp.action):
                res.decision = self.rec.wait(  # the mark's own decision, or the question it made the robot ask
                    lambda: next((d for d in self.rec.since(t0, "decision")
                                  if d.command is None or d.verdict == Verdict.ASK), None),
                    step.timeout)
                if res.decision is None:
                    res.problems.append("the reasoner made no decision on the mark")
                elif res.decision.verdict == Verdict.ASK and step.confirm is not None:
                    self._answer(res, step.confirm)
        else:
            time.sleep(step.wait or 0.0)
        if exp is not None:
            self._check(res, t0, known_goals)
        else:
            self._settle(t0, known_goals)
        res.goals = [g for g in self.rec.since(t0, "goal") if g.goal_id not in known_goals]
        res.said = [s.text for s in self.rec.since(t0, "say")]
        res.seconds = time.monotonic() - t0
        time.sleep(GAP_S)
        return res

    def _answer(self, res: StepResult, words: str) -> None:
        """The robot asked back: say `words`; the answer's decision becomes the step's decision."""
        res.asked = res.decision
        t1 = time.monotonic()
        self.speak(words)
        answer = self._first_heard(t1, res.step.timeout)
        if answer is None:
            res.problems.append(f'the voice service published nothing for the answer "{words}"')
            res.decision = None
            return
        res.decision = self.rec.wait(lambda: self._decision_for(t1, answer), res.step.timeout)

    def _first_heard(self, t0: float, timeout: float) -> VoiceCommand | None:
        """The first VoiceCommand published since t0, waiting up to `timeout` for it."""
        return self.rec.wait(lambda: next(iter(self.rec.since(t0, "heard")), None), timeout)

    def _decision_for(self, t0: float, heard: VoiceCommand) -> Decision | None:
        for d in self.rec.since(t0, "decision"):
            if heard.command is not None and d.command == heard.command:
                return d
            if heard.command is None and d.command is None and d.reason.value == "not_understood":
                return d
        return None

    def _check(self, res: StepResult, t0: float, known_goals: set[str]) -> None:
        exp = res.step.expect
        assert exp is not None
        p = res.problems
        if exp.heard is not None and res.heard is not None and res.heard.command != exp.heard:
            p.append(f"heard {res.heard.command.value if res.heard.command else 'nothing'} "
                     f"({res.heard.text!r}), expected {exp.heard.value}")
        d = res.decision
        if d is not None:
            for name in ("verdict", "reason", "situation"):
                want = getattr(exp, name)
                if want is not None and getattr(d, name) != want:
                    p.append(f"{name} {getattr(d, name).value}, expected {want.value}")
        elif res.step.wait is not None and exp.situation is not None:
            last = next((e.msg for e in reversed(self.rec.events) if e.kind == "decision"), None)
            if last is None or last.situation != exp.situation:
                p.append(f"situation {last.situation.value if last else 'unknown'}, expected {exp.situation.value}")
        if exp.action is not None:
            got = self.rec.wait(lambda: any(g.action == exp.action for g in self._new_goals(t0, known_goals)),
                                res.step.timeout)
            if not got:
                p.append(f"no {exp.action.value} goal was sent")
        if exp.no_action:
            time.sleep(0.5)
            extra = self._new_goals(t0, known_goals)
            if extra:
                p.append(f"unexpected motion goal(s): {', '.join(g.action.value for g in extra)}")
        if exp.said is not None:
            spoken = self.rec.wait(lambda: any(s.speaking and exp.said in (s.text or "")
                                               for s in self.rec.since(t0, "speaking")), res.step.timeout)
            if not spoken:
                p.append(f'the robot did not say "{exp.said}"')
        if exp.posture is not None:
            ok = self.rec.wait(lambda: self._settled_in(exp.posture, self._new_goals(t0, known_goals)),
                               res.step.timeout)
            res.posture = self.rec.latest_state.posture if self.rec.latest_state else None
            if not ok:
                p.append(f"posture {res.posture.value if res.posture else 'unknown'}, expected {exp.posture.value}")
        else:
            self._settle(t0, known_goals)

    def _new_goals(self, t0: float, known: set[str]) -> list[MotionGoal]:
        return [g for g in self.rec.since(t0, "goal") if g.goal_id not in known]

    def _settled_in(self, posture: Posture, new_goals: list[MotionGoal]) -> bool:
        """In `posture` and idle (or walking), with the motion service past the step's last goal."""
        s: MotionState | None = self.rec.latest_state
        if s is None or s.posture != posture or (s.action is not None and posture != Posture.WALKING):
            return False
        return not new_goals or s.goal_id == new_goals[-1].goal_id

    def _settle(self, t0: float, known_goals: set[str], timeout: float = SETTLE_S) -> None:
        """Wait until the robot has taken up the step's goals, is idle (or steadily walking) and silent."""

        def idle() -> bool:
            s = self.rec.latest_state
            if s is None or not self._settled_in(s.posture, self._new_goals(t0, known_goals)):
                return False
            return not (self.rec.latest_speech is not None and self.rec.latest_speech.speaking)

        self.rec.wait(idle, timeout)
