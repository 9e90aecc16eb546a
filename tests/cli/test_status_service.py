"""`hri status --service NAME`, the containers' health check: 0 only when that service is alive and ok."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from schemas import HealthStatus
from services.runtime import ServiceContext
from tests.conftest import ROOT, wait_for


def status(router_endpoint: str, robot_id: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("HRI_", "ZENOH_"))}
    return subprocess.run([sys.executable, "-m", "services.cli", "status", "--connect", router_endpoint,
                           "--robot", robot_id, *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=60, env=env)


def test_one_service_health_check(router_endpoint: str, robot_id: str, bus: ServiceContext, tmp_path: Path,
                                  start_service: Callable[..., subprocess.Popen[bytes]]) -> None:
    start_service("speech", env={"HRI_SPEECH_OUT": str(tmp_path / "speech")})
    health = wait_for(lambda: bus.query_health("speech", 1.0), 30)
    assert health.status is HealthStatus.OK
    ok = status(router_endpoint, robot_id, "--service", "speech")
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "speech" in ok.stdout and "vision" not in ok.stdout  # only the one asked about
    missing = status(router_endpoint, robot_id, "--service", "vision")
    assert missing.returncode == 1
    assert status(router_endpoint, robot_id).returncode == 1  # not all five are up


def test_a_scenario_waits_for_every_service_and_names_those_not_on_the_bus(
        bus: ServiceContext, tmp_path: Path, start_service: Callable[..., subprocess.Popen[bytes]]) -> None:
    """`hri demo` and the system tests start only when all five are up: a word spoken before the voice service
    listens, or a refusal before the speech service is up, would be lost."""
    from services.cli.recorder import Recorder
    from services.cli.runner import ScenarioRunner

    start_service("speech", env={"HRI_SPEECH_OUT": str(tmp_path / "speech")})
    wait_for(lambda: bus.query_health("speech", 1.0), 30)
    runner = ScenarioRunner(bus, Recorder(bus), tmp_path / "spool")
    missing = runner.wait_ready(timeout=3.0)
    assert "motion, reasoner, vision, voice on the bus" in missing, missing
