"""A "go" right after speech that matched no command is asked about ("don't ... go"), however sure, on the real Soar
kernel (agent/56_after_unclear.soar; the window is the "go" item's ^ask-after-unclear in knowledge.soar)."""

from __future__ import annotations

import pytest

from services.reasoner.agent_host import Memory, RememberOutput, SoarAgent
from tests.reasoner.conftest import Clock, decisions, motions, only_decision, say, seen, spoken
from tests.reasoner.test_confirm import ASK, REFUSAL
from tests.reasoner.test_explain import text, why

T = 1_000_000.0


def before(agent: SoarAgent, word: str | None = None, stamp: float = T) -> None:
    """Something said first: by default speech that matched no command."""
    agent.step(posture="standing")
    agent.step(say(word, confidence=0.3 if word is None else 0.9, stamp=stamp))


@pytest.mark.parametrize("after_s", [0.1, 0.8, 1.9])
def test_a_sure_go_just_after_unclear_speech_asks(agent: SoarAgent, clock: Clock, after_s: float) -> None:
    before(agent)
    outs = agent.step(say("go", confidence=0.97, stamp=T + after_s))
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action, d.say) == ("go", "ask", "confirm", None, ASK)
    assert motions(outs) == [] and spoken(outs) == [ASK]


@pytest.mark.parametrize("after_s", [2.0, 2.5, 30.0])
def test_a_sure_go_later_walks(agent: SoarAgent, after_s: float) -> None:
    before(agent)
    assert motions(agent.step(say("go", confidence=0.97, stamp=T + after_s))) == ["walk_forward"]


def test_a_sure_go_alone_walks(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    assert motions(agent.step(say("go", confidence=0.97, stamp=T))) == ["walk_forward"]


def test_the_question_is_the_dialogue_of_an_unsure_go(agent: SoarAgent, clock: Clock) -> None:
    before(agent)
    agent.step(say("go", confidence=0.97, stamp=T + 1))
    outs = agent.step(say("no", stamp=T + 1.3))
    assert motions(outs) == [] and only_decision(outs).say == "All right, I will not walk."
    # a "no" is not unclear speech: the window is still the first utterance's
    assert only_decision(agent.step(say("go", confidence=0.97, stamp=T + 1.8))).verdict == "ask"
    assert motions(agent.step(say("yes", confidence=0.9, stamp=T + 3))) == ["walk_forward"]


def test_silence_cancels(agent: SoarAgent, clock: Clock) -> None:
    before(agent)
    agent.step(say("go", confidence=0.97, stamp=T + 1))
    clock.now += 6
    d = only_decision(agent.step())
    assert (d.verdict, d.reason) == ("ignore", "confirm")
    assert motions(agent.step(say("yes", stamp=T + 8))) == ["nod"]


def test_only_the_newest_unclear_speech_counts(agent: SoarAgent, clock: Clock) -> None:
    before(agent, stamp=T)
    before(agent, stamp=T + 3)
    assert only_decision(agent.step(say("go", confidence=0.97, stamp=T + 4))).verdict == "ask"
    before(agent, stamp=T + 10)
    assert motions(agent.step(say("go", confidence=0.97, stamp=T + 12.5))) == ["walk_forward"]


def test_a_known_word_heard_too_unsurely_is_not_unclear_speech(agent: SoarAgent) -> None:
    """A quiet "go" said again louder walks: only speech that matched no command opens the window."""
    agent.step(posture="standing")
    assert only_decision(agent.step(say("go", confidence=0.4, stamp=T))).reason == "not_understood"
    assert motions(agent.step(say("go", confidence=0.97, stamp=T + 1))) == ["walk_forward"]


@pytest.mark.parametrize("first", ["stand", "stop", "no", "why"])
def test_a_command_before_the_go_is_the_persons_own_sequence(agent: SoarAgent, first: str) -> None:
    """"stop", then "go" a second later (the paper's scenario, quickly): no question."""
    before(agent, first)
    assert motions(agent.step(say("go", confidence=0.97, stamp=T + 1))) == ["walk_forward"]


def test_go_said_again_keeps_the_window_of_what_came_before(agent: SoarAgent, clock: Clock) -> None:
    before(agent)
    assert only_decision(agent.step(say("go", confidence=0.97, stamp=T + 0.5))).verdict == "ask"
    assert only_decision(agent.step(say("go", confidence=0.97, stamp=T + 1.5))).verdict == "ask"
    assert motions(agent.step(say("go", confidence=0.97, stamp=T + 2.5))) == ["walk_forward"]


@pytest.mark.parametrize(("word", "action"), [("down", ["sit_down"]), ("yes", ["nod"]), ("no", ["shake_head"])])
def test_other_commands_are_obeyed_at_once(agent: SoarAgent, word: str, action: list[str]) -> None:
    """Only "go" has an ^ask-after-unclear: "don't ... sit down" sitting is not a danger."""
    before(agent)
    outs = agent.step(say(word, confidence=0.97, stamp=T + 0.5))
    assert only_decision(outs).verdict == "obey" and motions(outs) == action


def test_in_danger_it_is_refused_and_the_o_asks(agent: SoarAgent, clock: Clock) -> None:
    agent.step(posture="standing")
    agent.step(seen("X", stamp=T - 1))
    agent.step(say(None, confidence=0.3, stamp=T))
    outs = agent.step(say("go", confidence=0.97, stamp=T + 1))
    assert (only_decision(outs).verdict, spoken(outs)) == ("refuse", [REFUSAL])
    assert RememberOutput(Memory("danger", resume_go=True, resume_asks=True)) in outs
    outs = agent.step(seen("O", stamp=T + 10))
    assert motions(outs) == [] and only_decision(outs).verdict == "ask"
    assert motions(agent.step(say("yes", confidence=0.9, stamp=T + 11))) == ["walk_forward"]


def test_why_says_it_asked_because_of_the_unclear_speech(agent: SoarAgent, clock: Clock) -> None:
    before(agent)
    agent.step(say("go", confidence=0.97, stamp=T + 1))
    said = text(why(agent, stamp=T + 2))
    assert said == "You said something I did not understand just before 'go', so I asked first."


def test_why_after_an_unsure_go_alone_still_says_unsure(agent: SoarAgent, clock: Clock) -> None:
    agent.step(posture="standing")
    agent.step(say("go", confidence=0.6, stamp=T))
    assert text(why(agent, stamp=T + 5)) == "I was not sure I heard 'go', so I asked first."
    outs = agent.step(say("go", confidence=0.97, stamp=T + 6))  # the why cancelled the question; no window opened
    assert motions(outs) == ["walk_forward"] and [d.verdict for d in decisions(outs)] == ["obey"]
