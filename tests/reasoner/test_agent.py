"""The Soar agent driven directly (no Zenoh): scripted sequences from issue #3."""

from __future__ import annotations

import pytest

from services.reasoner.agent_host import Memory, MotionOutput, RememberOutput, SoarAgent
from tests.reasoner.conftest import decisions, motions, only_decision, say, seen, spoken

REFUSAL = "Sorry, I cannot do it."


def test_paper_sequence(agent: SoarAgent) -> None:
    """sit, stand, yes, no, go, stop, X, go refused, O resumes, down (paper Fig. 12)."""
    assert agent.step(posture="sitting") == []
    outs = agent.step(say("stand", stamp=1.0))
    assert motions(outs) == ["stand_up"]
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action) == ("stand", "obey", "ok", "stand_up")
    assert d.situation == "safe"
    assert d.cause_stamp == 1.0
    agent.step(posture="standing")
    assert motions(agent.step(say("yes"))) == ["nod"]
    assert motions(agent.step(say("no"))) == ["shake_head"]
    outs = agent.step(say("go", stamp=5.0))
    walk = [o for o in outs if isinstance(o, MotionOutput)]
    assert [(w.action, w.sustain, w.cause_stamp) for w in walk] == [("walk_forward", True, 5.0)]
    agent.step(posture="walking")
    assert motions(agent.step(say("stop"))) == ["stop"]
    agent.step(posture="standing")
    outs = agent.step(seen("X"))
    assert motions(outs) == []  # standing still: nothing to stop
    d = only_decision(outs)
    assert (d.command, d.reason, d.situation) == (None, "danger_sign", "danger")
    outs = agent.step(say("go", stamp=9.0))
    d = only_decision(outs)
    assert (d.verdict, d.reason, d.say, d.situation) == ("refuse", "danger_sign", REFUSAL, "danger")
    assert spoken(outs) == [REFUSAL] and motions(outs) == []
    outs = agent.step(seen("O", stamp=10.0))
    d = only_decision(outs)
    assert (d.situation, d.action) == ("safe", "walk_forward")
    assert motions(outs) == ["walk_forward"]
    assert [o.cause_stamp for o in outs if isinstance(o, MotionOutput)] == [10.0]
    agent.step(posture="walking")
    outs = agent.step(say("down"))
    assert motions(outs) == ["sit_down"]
    assert only_decision(outs).verdict == "obey"


@pytest.mark.parametrize("shape", ["X", "TRIANGLE"])
def test_danger_while_walking_stops_first(agent: SoarAgent, shape: str) -> None:
    agent.step(posture="standing")
    agent.step(say("go"))
    agent.step(posture="walking")
    outs = agent.step(seen(shape, stamp=3.0))
    assert isinstance(outs[0], MotionOutput) and outs[0].action == "stop"  # before anything else
    assert outs[0].cause_stamp == 3.0
    d = only_decision(outs)
    assert (d.reason, d.action, d.situation) == ("danger_sign", "stop", "danger")
    assert RememberOutput(Memory("danger", False)) in outs


def test_danger_wins_over_o_in_the_same_observation(agent: SoarAgent) -> None:
    assert only_decision(agent.step(seen("X", "O"))).situation == "danger"
    assert agent.step(seen("O", "TRIANGLE")) == []  # still danger: no change, no decision


def test_go_while_sitting_stands_up_first(agent: SoarAgent) -> None:
    agent.step(posture="sitting")
    outs = agent.step(say("go", stamp=2.0))
    assert motions(outs) == ["stand_up"]
    assert only_decision(outs).action == "walk_forward"
    # The walk operator is stuck in an operator no-change impasse until the legs are up.
    stack = agent.execute("print --stack")[1]
    assert "(walk)" in stack and "operator no-change" in stack
    assert agent.step(posture="moving") == []
    outs = agent.step(posture="standing")
    assert [(o.action, o.cause_stamp, o.sustain) for o in outs if isinstance(o, MotionOutput)] == [
        ("walk_forward", 2.0, True)
    ]
    assert decisions(outs) == []  # one decision per command, already made
    assert "(walk)" not in agent.execute("print --stack")[1]


def test_danger_during_stand_up_cancels_the_walk(agent: SoarAgent) -> None:
    agent.step(posture="sitting")
    agent.step(say("go"))
    outs = agent.step(seen("X"))
    assert motions(outs) == ["stop"]
    assert motions(agent.step(posture="standing")) == []


def test_unknown_speech_is_not_understood(agent: SoarAgent) -> None:
    outs = agent.step(say(None, confidence=0.8))
    d = only_decision(outs)
    assert (d.command, d.verdict, d.reason, d.action) == (None, "ignore", "not_understood", None)
    assert spoken(outs) == ["Sorry, I did not understand."] and motions(outs) == []


def test_confidence_thresholds_come_from_semantic_memory(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    d = only_decision(agent.step(say("go", confidence=0.45)))
    assert (d.command, d.reason) == ("go", "not_understood")
    assert only_decision(agent.step(say("stop", confidence=0.35))).reason == "already_done"  # understood
    assert only_decision(agent.step(say("yes", confidence=0.29))).reason == "not_understood"
    assert motions(agent.step(say("yes", confidence=0.3))) == ["nod"]
    d = only_decision(agent.step(say("go", confidence=0.5)))  # understood, but unsure: ask
    assert (d.command, d.verdict, d.reason) == ("go", "ask", "confirm")
    assert motions(agent.step(say("go", confidence=0.85))) == ["walk_forward"]
    # The numbers are not in Python: they are recalled from semantic memory.
    wm = agent.execute("print --depth 3 s1")[1]
    assert "^min-confidence 0.5" in wm and "^confirm-below 0.85" in wm


def test_repeated_commands(agent: SoarAgent) -> None:
    agent.step(posture="sitting")
    outs = agent.step(say("down"))
    d = only_decision(outs)
    assert (d.verdict, d.reason) == ("ignore", "already_done")
    assert motions(outs) == [] and spoken(outs) == []
    agent.step(posture="standing")
    assert motions(agent.step(say("go"))) == ["walk_forward"]
    outs = agent.step(say("go"))
    assert only_decision(outs).reason == "already_done" and motions(outs) == []
    assert len(decisions(agent.step(seen("X")))) == 1
    for _ in range(3):
        assert agent.step(seen("X")) == []  # the same situation: no new decision
    agent.step(posture="standing")
    assert only_decision(agent.step(say("stop"))).reason == "already_done"


def test_other_commands_are_obeyed_in_danger(agent: SoarAgent) -> None:
    agent.step(seen("TRIANGLE"), posture="standing")
    assert motions(agent.step(say("yes"))) == ["nod"]
    assert motions(agent.step(say("no"))) == ["shake_head"]
    assert motions(agent.step(say("down"))) == ["sit_down"]
    agent.step(posture="sitting")
    assert motions(agent.step(say("stand"))) == ["stand_up"]
    agent.step(posture="walking")  # whatever moved the legs, danger means stop
    assert "stop" in motions(agent.step(say("stop")))


def test_resume_only_when_nothing_came_after_the_refused_go(agent: SoarAgent) -> None:
    agent.step(seen("X"), posture="standing")
    agent.step(say("go"))
    agent.step(say("yes"))
    outs = agent.step(seen("O"))
    assert only_decision(outs).action is None and motions(outs) == []


def test_busy_while_a_motion_runs(agent: SoarAgent) -> None:
    agent.step(posture="moving")
    outs = agent.step(say("yes"))
    d = only_decision(outs)
    assert (d.verdict, d.reason) == ("refuse", "busy") and motions(outs) == []
    agent.step(posture="walking")
    assert only_decision(agent.step(say("no"))).reason == "busy"


def test_restored_danger_is_still_latched(agent: SoarAgent) -> None:
    assert agent.reset(Memory("danger", False)) == Memory("danger", False)
    agent.step(posture="standing")
    d = only_decision(agent.step(say("go")))
    assert (d.verdict, d.reason) == ("refuse", "danger_sign")


def test_restored_refused_go_resumes_on_o(agent: SoarAgent) -> None:
    agent.reset(Memory("danger", True))
    assert motions(agent.step(seen("O"), posture="standing")) == ["walk_forward"]


def test_guard_stops_a_walking_robot_in_danger(agent: SoarAgent) -> None:
    agent.reset(Memory("danger", False))
    assert motions(agent.step(posture="walking")) == ["stop"]
    assert motions(agent.step(posture="walking")) == []  # once per walking episode
    agent.step(posture="standing")
    assert motions(agent.step(posture="walking")) == ["stop"]


def test_working_memory_stays_bounded(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    agent.step(say("yes"), say("no"), seen("X"), seen("O"))
    before = agent.wm_size()
    words = ["yes", "no", None, "stop", "go", "down", "stand"]
    for i in range(600):
        agent.submit(say(words[i % len(words)], stamp=float(i)))
        agent.submit(seen(["X", "O", "TRIANGLE"][i % 3]))
    outs = agent.pump()
    assert len(decisions(outs)) >= 600
    assert agent.pending() == 0
    assert agent.wm_size() <= before + 40, (before, agent.wm_size())


def test_outputs_of_a_batch_keep_input_order(agent: SoarAgent) -> None:
    agent.step(posture="standing")
    outs = agent.step(say("go"), seen("X"), say("go"))
    ds = decisions(outs)
    assert [(d.command, d.verdict) for d in ds] == [("go", "obey"), (None, "obey"), ("go", "refuse")]
    # The X came before the walk goal went out: no walk at all, and a stop for the intent.
    assert motions(outs) == ["stop"]


def test_soar_commands_run_on_the_live_agent(agent: SoarAgent) -> None:
    ok, out = agent.execute("print s1")
    assert ok and "^situation safe" in out
    ok, out = agent.execute("no-such-command")
    assert not ok and out
