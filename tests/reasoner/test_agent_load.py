"""Agents built for one test each: start-up errors and guarded callbacks.

Kept apart from the modules that share one agent: in soar-sml 9.6.5, shutting a kernel down
while another is alive in the process breaks the other's callbacks (checked), so these tests
must never overlap a shared agent's lifetime.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from services.reasoner.agent_host import AGENT_DIR, AgentConfig, AgentLoadError, SoarAgent
from tests.reasoner.conftest import motions, say


def test_a_failing_output_sink_is_not_fatal() -> None:
    def sink(_out: object) -> None:
        raise RuntimeError("boom")

    with SoarAgent(on_output=sink) as agent:
        assert motions(agent.step(say("yes"), posture="standing")) == ["nod"]
        assert agent.callback_errors >= 1


def _copy_rules(tmp_path: Path) -> Path:
    rules = tmp_path / "agent"
    shutil.copytree(AGENT_DIR, rules)
    return rules


def test_bad_rule_is_a_startup_error_naming_file_and_production(tmp_path: Path) -> None:
    rules = _copy_rules(tmp_path)
    (rules / "55_bad.soar").write_text(
        "sp {hri*fine (state <s> ^a b) --> (<s> ^c d)}\n"
        "sp {hri*broken (state <s> ^a b) --> (<unbound> ^c d)}\n"
    )
    with pytest.raises(AgentLoadError, match=r"55_bad\.soar.*hri\*broken"):
        SoarAgent(AgentConfig(rules_dir=rules, knowledge_file=rules / "knowledge.soar"))


def test_missing_knowledge_is_a_startup_error(tmp_path: Path) -> None:
    rules = _copy_rules(tmp_path)
    empty = tmp_path / "empty.soar"
    empty.write_text("# no knowledge\n")
    with pytest.raises(AgentLoadError, match="did not report ready"):
        SoarAgent(AgentConfig(rules_dir=rules, knowledge_file=empty))
    with pytest.raises(AgentLoadError, match="not found"):
        SoarAgent(AgentConfig(rules_dir=rules, knowledge_file=tmp_path / "nope.soar"))


def test_a_malformed_output_command_is_reported_and_dropped(tmp_path: Path) -> None:
    rules = _copy_rules(tmp_path)
    (rules / "55_malformed.soar").write_text(
        "sp {hri*apply*respond*malformed\n"
        "   (state <s> ^operator.name respond ^io.output-link <out>)\n"
        "-->\n"
        "   (<out> ^motion <m>) (<m> ^speed fast)}\n"
    )
    with SoarAgent(AgentConfig(rules_dir=rules, knowledge_file=rules / "knowledge.soar")) as agent:
        assert motions(agent.step(say("yes"), posture="standing")) == ["nod"]  # the bad one is dropped
        assert "^output-link I3" in agent.execute("print i1")[1]
        ok, output_link = agent.execute("print --depth 2 i3")
        assert ok and "^motion" not in output_link  # marked with an error status, then cleaned up
