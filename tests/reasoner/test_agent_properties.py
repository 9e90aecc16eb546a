"""Property test: random sequences of commands (with "why", unsure "go"s and "yes" answers at
various confidences), marks, motion states and the passing of time (a question's timeout) never
break the safety invariants 1 and 2 of DESIGN.md, checked after every step; "why" never moves."""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from services.reasoner.agent_host import (
    POSTURES,
    CommandInput,
    ExplanationOutput,
    MarksInput,
    Memory,
    SoarAgent,
)
from tests.reasoner.conftest import decisions, motions

DANGER = {"X", "TRIANGLE"}


@dataclass(frozen=True)
class PostureChange:
    """The motion service reports an arbitrary posture."""

    posture: str


@dataclass(frozen=True)
class MotionFollows:
    """The motion service reports the posture its last goal leads to (so walking happens often)."""


@dataclass(frozen=True)
class TimePasses:
    """Seconds go by on the agent's timer clock (an open question may time out)."""

    seconds: float


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


Step = CommandInput | MarksInput | PostureChange | MotionFollows | TimePasses

AFTER_GOAL = {"stand_up": "standing", "sit_down": "sitting", "walk_forward": "walking", "stop": "standing"}


# Weighted so that walking, and danger while walking, come up in most examples.
commands = st.builds(
    CommandInput,
    word=st.sampled_from(["stand", "down", "yes", "yes", "no", "go", "go", "go", "stop", "why", None]),
    confidence=st.sampled_from([0.3, 0.45, 0.5, 0.6, 0.69, 0.7, 0.8, 0.85, 1.0]),
)
observations = st.builds(
    MarksInput,
    shapes=st.sampled_from(
        [frozenset(), frozenset({"X"}), frozenset({"TRIANGLE"}), frozenset({"O"}), frozenset({"O"}),
         frozenset({"O"}), frozenset({"X", "O"})]
    ),
)
postures = st.builds(PostureChange, posture=st.sampled_from(POSTURES))
BY_KIND = {
    "command": commands, "marks": observations, "posture": postures, "follow": st.just(MotionFollows()),
    "time": st.builds(TimePasses, seconds=st.sampled_from([1.0, 6.0])),
}
KINDS = ["command"] * 4 + ["marks"] * 2 + ["posture"] + ["follow"] * 3 + ["time"]
step = st.sampled_from(KINDS).flatmap(BY_KIND.__getitem__)
steps = st.lists(step, min_size=8, max_size=40)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(sequence=steps, restored_danger=st.booleans())
def test_safety_invariants_hold_after_every_step(
    shared_agent: SoarAgent, sequence: list[Step], restored_danger: bool
) -> None:
    shared_agent.reset(Memory("danger" if restored_danger else "safe", False))
    clock = Clock()
    shared_agent.clock = clock
    latched = restored_danger  # an X or triangle seen, and no O-only observation since
    walking = False  # the last motion goal published was walk_forward (kept alive)
    posture = "unknown"  # where the motion service would take the robot
    for step in sequence:
        if isinstance(step, PostureChange):
            outs = shared_agent.step(posture=step.posture)
        elif isinstance(step, MotionFollows):
            outs = shared_agent.step(posture=posture)
        elif isinstance(step, TimePasses):
            clock.now += step.seconds
            outs = shared_agent.step()
        else:
            outs = shared_agent.step(step)
        sent = motions(outs)
        if isinstance(step, MarksInput) and step.shapes & DANGER:
            latched = True
            # Invariant 2: an X or triangle seen while walking produces a stop goal.
            if walking:
                assert "stop" in sent, (step, outs)
        elif isinstance(step, MarksInput) and "O" in step.shapes:
            latched = False
        # Invariant 1: once an X or triangle has been seen, no walk goal until an O is seen.
        if latched:
            assert "walk_forward" not in sent, (step, outs)
        if sent:
            walking = sent[-1] == "walk_forward"
            posture = AFTER_GOAL.get(sent[-1], posture)
        # One answer per command, always (a decision, or for "why" an explanation, which never
        # moves the robot); marks decide only on a change of situation.
        explained = [o for o in outs if isinstance(o, ExplanationOutput)]
        if isinstance(step, CommandInput) and step.word == "why" and step.confidence >= 0.3:
            assert len(explained) == 1 and decisions(outs) == [] and sent == [], (step, outs)
        elif isinstance(step, CommandInput):
            assert len(decisions(outs)) == 1 and explained == [], (step, outs)
        for d in decisions(outs):
            assert d.situation == ("danger" if latched else "safe"), (step, d)
