"""Property test: random sequences of commands, marks and motion states never break the
safety invariants 1 and 2 of DESIGN.md, checked after every step."""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from services.reasoner.agent_host import POSTURES, CommandInput, MarksInput, Memory, SoarAgent
from tests.reasoner.conftest import decisions, motions

DANGER = {"X", "TRIANGLE"}


@dataclass(frozen=True)
class PostureChange:
    """The motion service reports an arbitrary posture."""

    posture: str


@dataclass(frozen=True)
class MotionFollows:
    """The motion service reports the posture its last goal leads to (so walking happens often)."""


Step = CommandInput | MarksInput | PostureChange | MotionFollows

AFTER_GOAL = {"stand_up": "standing", "sit_down": "sitting", "walk_forward": "walking", "stop": "standing"}


# Weighted so that walking, and danger while walking, come up in most examples.
commands = st.builds(
    CommandInput,
    word=st.sampled_from(["stand", "down", "yes", "no", "go", "go", "go", "stop", None]),
    confidence=st.sampled_from([0.3, 0.45, 0.8, 1.0]),
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
    "command": commands, "marks": observations, "posture": postures, "follow": st.just(MotionFollows())
}
KINDS = ["command"] * 3 + ["marks"] * 2 + ["posture"] + ["follow"] * 3
step = st.sampled_from(KINDS).flatmap(BY_KIND.__getitem__)
steps = st.lists(step, min_size=8, max_size=40)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(sequence=steps, restored_danger=st.booleans())
def test_safety_invariants_hold_after_every_step(
    shared_agent: SoarAgent, sequence: list[Step], restored_danger: bool
) -> None:
    shared_agent.reset(Memory("danger" if restored_danger else "safe", False))
    latched = restored_danger  # an X or triangle seen, and no O-only observation since
    walking = False  # the last motion goal published was walk_forward (kept alive)
    posture = "unknown"  # where the motion service would take the robot
    for step in sequence:
        if isinstance(step, PostureChange):
            outs = shared_agent.step(posture=step.posture)
        elif isinstance(step, MotionFollows):
            outs = shared_agent.step(posture=posture)
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
        # One decision per command, always; marks decide only on a change of situation.
        if isinstance(step, CommandInput):
            assert len(decisions(outs)) == 1, (step, outs)
        for d in decisions(outs):
            assert d.situation == ("danger" if latched else "safe"), (step, d)
