"""The episodic store on disk: it survives a restart (also after SIGKILL-like exits, since every
episode is committed) and stays within its bound. Each test owns its kernel, one at a time."""

from __future__ import annotations

from pathlib import Path

from services.reasoner.agent_host import AgentConfig, ExplanationOutput, Memory, SoarAgent
from services.reasoner.explain import render
from tests.reasoner.conftest import motions, say, seen

NOW = 2_000_000.0


def explain(agent: SoarAgent) -> ExplanationOutput:
    outs = agent.step(say("why", stamp=NOW))
    found = [o for o in outs if isinstance(o, ExplanationOutput)]
    assert len(found) == 1 and motions(outs) == []
    return found[0]


def test_a_restarted_agent_explains_a_danger_latched_before(tmp_path: Path) -> None:
    db = tmp_path / "state folder" / "episodes.db"  # a space, as in many home folders
    with SoarAgent(AgentConfig(episodes=db)) as before:
        before.step(posture="standing")
        before.step(seen("TRIANGLE", stamp=NOW - 40))
        before.step(say("go", stamp=NOW - 35))
    assert db.is_file()
    # The danger itself comes back from reasoner.json (the service's job); the why from the episodes.
    with SoarAgent(AgentConfig(episodes=db), Memory("danger", True)) as after:
        out = explain(after)
        assert out.template == "refused-danger"
        assert render(out, NOW) == "I saw a triangle 40 seconds ago, and no O since. Show me an O and I will walk."
        # a decision after the restart is the newest, and the old cause is still found
        after.step(say("go", stamp=NOW - 1))
        out = explain(after)
        assert out.decision is not None and out.decision.cause_stamp == NOW - 1
        assert [e.stamp for e in out.evidence if e.role == "cause"] == [NOW - 40]


def test_the_store_is_rotated_at_its_bound(tmp_path: Path) -> None:
    db = tmp_path / "episodes.db"
    bound = 450_000  # an empty store is about 380 kB; a decision adds about 0.7 kB
    with SoarAgent(AgentConfig(episodes=db, episodes_max_bytes=bound)) as agent:
        agent.step(posture="standing")
        for i in range(700):
            agent.step(say(("stand", "down", "yes", "no")[i % 4], stamp=NOW - 100 + i * 0.01))
            assert db.stat().st_size <= bound + 64 * 1024  # checked after every pump: one page-group over at most
        assert agent.episode_rotations >= 1
        assert (tmp_path / "episodes.db.1").is_file()
        agent.step(seen("X", stamp=NOW - 5))
        assert render(explain(agent), NOW) == "I saw an X mark 5 seconds ago. I will not walk until I see an O."
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episodes.db", "episodes.db.1"]
