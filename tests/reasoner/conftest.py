"""One Soar kernel per test module, re-initialised (init-soar, a few ms) for every test."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from services.reasoner.agent_host import (
    CommandInput,
    DecisionOutput,
    MarksInput,
    Memory,
    MotionOutput,
    Output,
    SayOutput,
    SoarAgent,
)


@pytest.fixture(scope="module")
def shared_agent() -> Iterator[SoarAgent]:
    with SoarAgent() as agent:
        yield agent


@pytest.fixture
def agent(shared_agent: SoarAgent) -> SoarAgent:
    shared_agent.reset(Memory())
    return shared_agent


class Clock:
    """The agent's timer clock, moved by hand."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(agent: SoarAgent) -> Clock:
    clock = Clock()
    agent.clock = clock
    return clock


def say(word: str | None, confidence: float = 0.9, stamp: float | None = None) -> CommandInput:
    return CommandInput(word=word, confidence=confidence, stamp=stamp)


def seen(*shapes: str, stamp: float | None = None) -> MarksInput:
    return MarksInput(shapes=frozenset(shapes), stamp=stamp)


def motions(outs: list[Output]) -> list[str]:
    return [o.action for o in outs if isinstance(o, MotionOutput)]


def decisions(outs: list[Output]) -> list[DecisionOutput]:
    return [o for o in outs if isinstance(o, DecisionOutput)]


def spoken(outs: list[Output]) -> list[str]:
    return [o.text for o in outs if isinstance(o, SayOutput)]


def only_decision(outs: list[Output]) -> DecisionOutput:
    found = decisions(outs)
    assert len(found) == 1, f"expected one decision, got {outs}"
    return found[0]
