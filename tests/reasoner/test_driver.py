"""The thread that owns the agent: start-up, input, Soar commands between pumps, stop."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.reasoner.agent_host import AgentConfig, AgentLoadError, Memory, MotionOutput, Output
from services.reasoner.driver import AgentDriver
from services.runtime import get_logger
from tests.conftest import wait_for
from tests.reasoner.conftest import say

LOG = get_logger("reasoner-test")


def test_driver_runs_the_agent_and_soar_commands() -> None:
    outs: list[Output] = []
    driver = AgentDriver(AgentConfig(), Memory("danger", False), outs.append, LOG)
    try:
        assert driver.start() == Memory("danger", False)
        driver.set_posture("standing")
        driver.submit(say("yes"))
        wait_for(lambda: any(isinstance(o, MotionOutput) and o.action == "nod" for o in outs), 5.0)
        ok, text = driver.run_command("print s1")
        assert ok and "^situation danger" in text
        with pytest.raises(ValueError, match="SIGTERM"):
            driver.run_command("exit")
        for forget in ("init-soar", "soar init", "is"):
            with pytest.raises(ValueError, match="latched situation"):
                driver.run_command(forget)
        with pytest.raises(ValueError, match="empty"):
            driver.run_command("   ")
        assert driver.responsive() and driver.backlog() == 0
    finally:
        driver.stop()
    assert not driver.is_alive() and not driver.responsive()


def test_driver_start_reports_the_load_error(tmp_path: Path) -> None:
    config = AgentConfig(knowledge_file=tmp_path / "missing.soar")
    driver = AgentDriver(config, Memory(), lambda _o: None, LOG)
    with pytest.raises(AgentLoadError, match=r"missing\.soar"):
        driver.start()
    driver.stop()
