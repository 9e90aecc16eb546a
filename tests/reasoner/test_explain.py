"""'Why?' answered from the agent's episodic memory (issue #15), on the real Soar kernel."""

from __future__ import annotations

import pytest

from services.reasoner.agent_host import ExplanationOutput, Output, SoarAgent
from services.reasoner.explain import explanation_model, render
from tests.reasoner.conftest import decisions, motions, say, seen

NOW = 1_000_000.0


def why(agent: SoarAgent, stamp: float = NOW) -> ExplanationOutput:
    outs = agent.step(say("why", stamp=stamp))
    assert motions(outs) == [] and decisions(outs) == []  # the host makes the Decision from it
    found = [o for o in outs if isinstance(o, ExplanationOutput)]
    assert len(found) == 1, outs
    return found[0]


def text(out: ExplanationOutput) -> str:
    return render(out, NOW)


def test_nothing_to_explain_yet(agent: SoarAgent) -> None:
    out = why(agent)
    assert (out.template, out.decision, out.episode, out.evidence) == ("nothing", None, None, ())
    assert text(out) == "I have not decided anything yet."


def test_refused_go_names_the_mark_that_latched_the_danger(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 14))
    agent.step(seen("X", stamp=NOW - 10))  # no news: no decision, no episode
    agent.step(say("go", stamp=NOW - 2))
    out = why(agent)
    assert out.template == "refused-danger"
    assert (out.decision.command, out.decision.verdict, out.decision.reason) == ("go", "refuse", "danger_sign")
    assert text(out) == "I saw an X mark 14 seconds ago, and no O since. Show me an O and I will walk."
    cause = [e for e in out.evidence if e.role == "cause"]
    assert [(e.kind, e.what, e.stamp) for e in cause] == [("mark", "X", NOW - 14)]
    assert cause[0].episode is not None and out.episode is not None and cause[0].episode < out.episode
    model = explanation_model(out, text(out), NOW)
    assert model.reason == "danger_sign" and model.episode == out.episode
    assert [(e.kind, e.what, e.ago_s) for e in model.evidence] == [("command", "go", 2.0), ("mark", "X", 14.0)]


def test_walking_is_explained_by_the_go(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(say("go", stamp=NOW - 6))
    assert text(why(agent)) == "You told me to go 6 seconds ago."


def test_resumed_walk_recalls_the_refused_go(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("TRIANGLE", stamp=NOW - 30))
    agent.step(say("go", stamp=NOW - 20))
    assert motions(agent.step(seen("O", stamp=NOW - 3))) == ["walk_forward"]
    out = why(agent)
    assert out.template == "resumed"
    assert text(out) == "I saw an O, so I carried out the 'go' you gave me 20 seconds ago."


def test_stop_caused_by_a_mark(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(say("go"))
    agent.step(posture="walking")
    agent.step(seen("TRIANGLE", "O", stamp=NOW - 3))
    out = why(agent)
    assert out.template == "stopped-danger"
    assert text(out) == "I stopped because I saw a triangle 3 seconds ago."


@pytest.mark.parametrize(
    ("setup", "expected"),
    [
        ([("posture", "sitting"), ("say", "down")], "I had already done that when you said 'down'."),
        ([("posture", "moving"), ("say", "stand")], "I was still moving when you said 'stand': that must finish first."),
        ([("say", None)], "I did not understand what you said."),
        ([("posture", "standing"), ("go", 0.4)], "I was not sure I heard 'go'."),
        ([("posture", "standing"), ("go", 0.6)], "I was not sure I heard 'go', so I asked first."),
        ([("posture", "standing"), ("go", 0.6), ("say", "yes")], "I asked whether to walk, and you said yes just now."),
        ([("posture", "standing"), ("go", 0.6), ("say", "no")], "I asked whether to walk, and you said no just now."),
        ([("posture", "standing"), ("say", "stand")], "I had already done that when you said 'stand'."),
        ([("posture", "sitting"), ("say", "stand")], "You told me to stand up just now."),
        ([("seen", "X"), ("seen", "O")], "I saw an O just now, so it is safe to walk again."),
        ([("seen", "X")], "I saw an X mark just now. I will not walk until I see an O."),
    ],
)
def test_the_condition_in_a_sentence(agent: SoarAgent, setup: list[tuple[str, object]], expected: str) -> None:
    for kind, value in setup:
        if kind == "posture":
            agent.step(posture=str(value))
        elif kind == "say":
            agent.step(say(value if value is None else str(value), stamp=NOW))  # type: ignore[arg-type]
        elif kind == "go":
            agent.step(say("go", confidence=float(value), stamp=NOW))  # type: ignore[arg-type]
        else:
            agent.step(seen(str(value), stamp=NOW))
    assert text(why(agent)) == expected


def test_why_is_not_itself_explained_and_never_moves(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(say("go", stamp=NOW - 6))
    first = why(agent)
    second = why(agent)
    assert first.template == second.template == "obeyed" and first.episode == second.episode
    assert motions(agent.step(posture="walking")) == []


def test_why_cancels_an_open_question(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(say("go", confidence=0.6, stamp=NOW - 1))
    assert why(agent).template == "asked"
    outs: list[Output] = agent.step(say("yes"))
    assert motions(outs) == ["nod"]  # the question was dropped: an ordinary yes


def test_the_store_holds_one_episode_per_decision(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    for word in ("go", "stop", "yes", "no"):
        agent.step(say(word))
    agent.step(seen("O"))  # no change of situation: no decision, no episode
    assert agent.execute("epmem --stats time")[1].strip() == "5"  # the next episode would be 5


def test_why_keeps_a_refused_go_waiting_for_the_o(agent: SoarAgent) -> None:
    """The demo's order: refused, asked why, then the O resumes the walk (paper Fig. 12g)."""
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 5))
    agent.step(say("go", stamp=NOW - 2))
    assert why(agent).template == "refused-danger"
    assert motions(agent.step(seen("O"))) == ["walk_forward"]


def test_a_cause_no_longer_in_the_store_is_said_plainly(agent: SoarAgent) -> None:
    """After a rotation of the store the mark's episode may be gone: no invented time."""
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 5))
    agent.step(say("go", stamp=NOW - 2))
    agent.execute("epmem --init")  # in memory: the episodes so far are gone
    agent.execute("epmem --set force remember")
    agent.step(say("go", stamp=NOW - 1))  # refused again; stored in the new store
    out = why(agent)
    assert out.template == "refused-danger" and [e for e in out.evidence if e.role == "cause"] == []
    assert text(out) == "I saw a danger sign before, and no O since. Show me an O and I will walk."


def test_a_burst_of_whys_gets_one_answer(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 5))
    agent.step(say("go", stamp=NOW - 2))
    for _ in range(3):
        agent.submit(say("why", stamp=NOW))
    found = [o for o in agent.pump() if isinstance(o, ExplanationOutput)]
    assert [o.template for o in found] == ["refused-danger"]
    assert why(agent).template == "refused-danger"  # and nothing was left half done


def test_a_why_during_the_recall_of_a_cause_is_not_confused_by_it(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 5))
    agent.step(say("go", stamp=NOW - 2))
    for gap in range(6):  # the second why lands at each stage of the first one's retrievals
        agent.submit(say("why", stamp=NOW))
        agent.execute(f"run {gap}")
        agent.submit(say("why", stamp=NOW))
        found = [o for o in agent.pump() if isinstance(o, ExplanationOutput)]
        assert found and all(o.template == "refused-danger" for o in found), (gap, found)
        assert [e.what for e in found[-1].evidence] == ["go", "X"], gap


def test_why_while_getting_up_for_a_walk_sends_no_second_stand_up(agent: SoarAgent) -> None:
    """Found by the property test: answering "why" took the top state's operator slot from the
    walk while the robot was still getting up, the stand-up substate vanished with it, and the walk's
    next impasse sent a second stand-up for the same "go"."""
    agent.step(posture="sitting")
    assert motions(agent.step(say("go", 0.9, stamp=NOW - 1))) == ["stand_up"]
    why(agent)  # asserts that answering moves nothing
    assert motions(agent.step(posture="sitting")) == []  # still the same walk: no second stand-up
    assert motions(agent.step(posture="standing")) == ["walk_forward"]
    agent.step(say("stop", stamp=NOW))
    agent.step(posture="sitting")
    assert motions(agent.step(say("go", 0.9, stamp=NOW + 1))) == ["stand_up"]  # a new walk stands up again


def test_why_after_an_o_asked_about_an_unsure_refused_go(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(seen("X", stamp=NOW - 20))
    agent.step(say("go", confidence=0.6, stamp=NOW - 10))  # refused: danger
    assert [d.verdict for d in decisions(agent.step(seen("O", stamp=NOW - 2)))] == ["ask"]
    answer = why(agent)
    assert answer.template == "asked"
    assert text(answer) == "I was not sure I heard 'go', so I asked first."
