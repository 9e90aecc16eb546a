"""The confirmation dialogue of an unsure "go" (issue #12), on the real Soar kernel."""

from __future__ import annotations

import pytest

from services.reasoner.agent_host import Memory, RememberOutput, SoarAgent
from tests.reasoner.conftest import Clock, decisions, motions, only_decision, say, seen, spoken

ASK = "Shall I walk forward?"
REFUSAL = "Sorry, I cannot do it."


def ask(agent: SoarAgent, confidence: float = 0.6, stamp: float = 1.0) -> None:
    agent.step(posture="standing")
    outs = agent.step(say("go", confidence=confidence, stamp=stamp))
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action, d.say) == ("go", "ask", "confirm", None, ASK)
    assert spoken(outs) == [ASK] and motions(outs) == []


@pytest.mark.parametrize("confidence", [0.5, 0.6, 0.84])
def test_unsure_go_asks_and_a_confident_yes_walks(agent: SoarAgent, clock: Clock, confidence: float) -> None:
    ask(agent, confidence)
    outs = agent.step(say("yes", confidence=0.7, stamp=2.0))
    assert motions(outs) == ["walk_forward"]  # and no nod: the yes is an answer
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action, d.cause_stamp) == ("yes", "obey", "ok", "walk_forward", 2.0)
    # the question is closed: its timer no longer does anything
    clock.now += 60
    assert agent.step() == []


@pytest.mark.parametrize("cycles", [0, 1, 2, 3, 4, 6, 9, 15])
def test_a_yes_that_comes_while_the_question_is_being_asked_is_answered(
    agent: SoarAgent, clock: Clock, cycles: int
) -> None:
    """A person may answer before the agent has settled after asking (the question's sub-goal, its timer):
    the "yes" is put in after `cycles` decision cycles of the "go" and must still carry it out. (The system
    test's lost "yes", stop 37, was looked for here: never lost.)"""
    agent.step(posture="standing")
    agent.submit(say("go", confidence=0.6, stamp=1.0))
    if cycles:
        ok, out = agent.execute(f"run {cycles}")
        assert ok, out
    agent.submit(say("yes", confidence=0.9, stamp=2.0))
    outs = agent.pump()
    yes = [d for d in decisions(outs) if d.command == "yes"]
    assert [(d.verdict, d.action) for d in yes] == [("obey", "walk_forward")]
    assert motions(outs) == ["walk_forward"]


def test_sure_go_walks_and_too_unsure_go_is_not_understood(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    assert only_decision(agent.step(say("go", confidence=0.49))).reason == "not_understood"
    assert motions(agent.step(say("go", confidence=0.85))) == ["walk_forward"]


def test_yes_while_sitting_stands_up_then_walks(agent: SoarAgent, clock: Clock) -> None:
    agent.step(posture="sitting")
    assert only_decision(agent.step(say("go", confidence=0.6))).verdict == "ask"
    assert motions(agent.step(say("yes"))) == ["stand_up"]
    assert motions(agent.step(posture="standing")) == ["walk_forward"]


def test_no_cancels_without_shaking_the_head(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    outs = agent.step(say("no", stamp=3.0))
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action) == ("no", "obey", "ok", None)
    assert motions(outs) == [] and spoken(outs) == ["All right, I will not walk."]
    # afterwards yes and no are ordinary commands again
    assert motions(agent.step(say("yes"))) == ["nod"]


def test_unsure_yes_cancels(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    outs = agent.step(say("yes", confidence=0.69))
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason) == ("yes", "ignore", "not_understood")
    assert motions(outs) == []
    assert motions(agent.step(say("yes"))) == ["nod"]  # the question is gone


@pytest.mark.parametrize(("word", "action"), [("stand", None), ("down", "sit_down"), ("stop", None)])
def test_another_command_cancels_and_is_answered(agent: SoarAgent, clock: Clock, word: str,
                                                  action: str | None) -> None:
    ask(agent)
    outs = agent.step(say(word))
    d = only_decision(outs)  # only that command's own decision: the question is dropped silently
    assert d.command == word
    assert motions(outs) == ([action] if action else [])
    outs = agent.step(say("yes"))
    assert "walk_forward" not in motions(outs)
    assert only_decision(outs).command == "yes"


def test_speech_not_understood_cancels(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    assert only_decision(agent.step(say(None, confidence=0.2))).reason == "not_understood"
    assert "walk_forward" not in motions(agent.step(say("yes")))


def test_silence_times_out(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    clock.now += 4.9
    assert agent.step() == []
    clock.now += 0.2  # the dialogue's 5 s (knowledge.soar) have passed
    outs = agent.step()
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action, d.say) == ("go", "ignore", "confirm", None, None)
    assert motions(outs) == []
    assert motions(agent.step(say("yes"))) == ["nod"]  # too late: an ordinary yes


def test_a_new_unsure_go_asks_again_with_its_own_timeout(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    clock.now += 3
    assert only_decision(agent.step(say("go", confidence=0.6))).verdict == "ask"
    clock.now += 3  # the first question's timer runs out: it was replaced, nothing happens
    assert agent.step() == []
    assert motions(agent.step(say("yes"))) == ["walk_forward"]


def test_danger_during_the_question_refuses_at_once(agent: SoarAgent, clock: Clock) -> None:
    ask(agent, stamp=1.0)
    outs = agent.step(seen("X"))
    found = decisions(outs)
    assert [(d.command, d.verdict, d.reason, d.situation) for d in found] == [
        (None, "obey", "danger_sign", "danger"),
        ("go", "refuse", "danger_sign", "danger"),
    ]
    assert found[1].cause_stamp == 1.0
    assert spoken(outs) == [REFUSAL]
    outs = agent.step(say("yes"))
    assert motions(outs) == ["nod"]
    # an unconfirmed go is not resumed by an O
    outs = agent.step(seen("O"))
    assert "walk_forward" not in motions(outs)


def test_danger_and_yes_together_refuse(agent: SoarAgent, clock: Clock) -> None:
    ask(agent)
    agent.submit(seen("TRIANGLE"))
    agent.submit(say("yes"))
    outs = agent.pump()
    assert "walk_forward" not in motions(outs)
    assert [(d.command, d.verdict, d.reason) for d in decisions(outs)] == [
        (None, "obey", "danger_sign"),
        ("yes", "refuse", "danger_sign"),
    ]


def refuse_unsure_go_in_danger(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("X"))
    outs = agent.step(say("go", confidence=0.6, stamp=1.0))
    d = only_decision(outs)
    assert (d.verdict, d.reason) == ("refuse", "danger_sign")
    assert spoken(outs) == [REFUSAL]
    assert RememberOutput(Memory("danger", resume_go=True, resume_asks=True)) in outs


def test_unsure_go_refused_in_danger_is_asked_about_when_an_o_clears_it(agent: SoarAgent,
                                                                         clock: Clock) -> None:
    refuse_unsure_go_in_danger(agent)
    outs = agent.step(seen("O", stamp=3.0))
    assert motions(outs) == []  # never walked on an unsure word ...
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.situation, d.say, d.cause_stamp) == (
        "go", "ask", "confirm", "safe", ASK, 3.0)
    assert spoken(outs) == [ASK]
    assert RememberOutput(Memory("safe")) in outs
    outs = agent.step(say("yes", confidence=0.7, stamp=4.0))  # ... only on a confident yes
    assert motions(outs) == ["walk_forward"]
    assert only_decision(outs).cause_stamp == 4.0


@pytest.mark.parametrize("answer", ["no", "stop", None])
def test_the_question_an_o_asks_is_cancelled_like_any_other(agent: SoarAgent, clock: Clock,
                                                            answer: str | None) -> None:
    refuse_unsure_go_in_danger(agent)
    agent.step(seen("O"))
    if answer is None:
        clock.now += 6  # silence: the dialogue's timeout
        outs = agent.step()
        assert (only_decision(outs).verdict, only_decision(outs).reason) == ("ignore", "confirm")
    else:
        outs = agent.step(say(answer))
    assert "walk_forward" not in motions(outs)
    assert "walk_forward" not in motions(agent.step(say("yes")))  # the question is gone


def test_a_danger_before_the_answer_refuses_the_question_an_o_asked(agent: SoarAgent, clock: Clock) -> None:
    refuse_unsure_go_in_danger(agent)
    agent.step(seen("O"))
    agent.step(seen())
    outs = agent.step(seen("TRIANGLE"))
    assert [(d.command, d.verdict, d.reason) for d in decisions(outs)] == [
        (None, "obey", "danger_sign"), ("go", "refuse", "danger_sign")]
    assert "walk_forward" not in motions(agent.step(say("yes")))


def test_restored_unsure_refused_go_asks_on_o(agent: SoarAgent, clock: Clock) -> None:
    agent.reset(Memory("danger", resume_go=True, resume_asks=True))
    outs = agent.step(seen("O"), posture="standing")
    assert motions(outs) == [] and only_decision(outs).verdict == "ask"


def test_a_sure_go_after_an_unsure_one_resumes_at_once(agent: SoarAgent, clock: Clock) -> None:
    refuse_unsure_go_in_danger(agent)
    agent.step(say("go", confidence=0.9))  # refused too, and remembered as sure: newest wins
    assert motions(agent.step(seen("O"))) == ["walk_forward"]
