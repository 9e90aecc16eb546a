"""docker-compose.yml and the Dockerfile, checked for structure (no Docker engine runs here)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import yaml

from schemas.keys import SERVICES

ROOT = Path(__file__).resolve().parents[2]
COMPOSE = yaml.safe_load((ROOT / "docker-compose.yml").read_text())


def test_router_is_zenohd_1_10_with_rest() -> None:
    zenoh = COMPOSE["services"]["zenoh"]
    assert re.fullmatch(r"eclipse/zenoh:1\.10(\.\d+)?", zenoh["image"])
    cmd = " ".join(zenoh["command"])
    assert "--rest-http-port 8000" in cmd and "tcp/0.0.0.0:7447" in cmd
    assert "7447:7447" in zenoh["ports"] and "8000:8000" in zenoh["ports"]


def test_every_service_runs_an_importable_module_against_the_router() -> None:
    assert set(COMPOSE["services"]) == {"zenoh", *SERVICES}
    router_port = re.search(r":(\d+)$", COMPOSE["services"]["zenoh"]["command"][1]).group(1)
    for name in SERVICES:
        svc = COMPOSE["services"][name]
        cmd = svc["command"]
        assert cmd[:2] == ["python", "-m"], cmd
        assert cmd[2] == f"services.{name}"
        assert importlib.util.find_spec(cmd[2]) is not None, cmd[2]
        assert importlib.util.find_spec(f"{cmd[2]}.__main__") is not None
        assert svc["environment"]["HRI_ZENOH_CONNECT"] == f"tcp/zenoh:{router_port}"
        assert svc["build"] == "." and "zenoh" in svc["depends_on"]


def test_devices_are_mapped_where_needed_with_simulation_default() -> None:
    services = COMPOSE["services"]
    assert any(d.endswith(":/dev/ttyUSB0") for d in services["motion"]["devices"])
    assert any(d.endswith(":/dev/video0") for d in services["vision"]["devices"])
    assert any(d.endswith(":/dev/snd") for d in services["voice"]["devices"])
    assert any(d.endswith(":/dev/snd") for d in services["speech"]["devices"])
    assert services["motion"]["environment"]["HRI_MOTION_SIM"] == "${HRI_MOTION_SIM:-1}"
    assert "devices" not in services["reasoner"]


def test_dockerfile_installs_the_package_and_speech_engine() -> None:
    text = (ROOT / "Dockerfile").read_text()
    assert "espeak-ng" in text and 'pip install --no-cache-dir ".[mic]"' in text
    assert "HRI_VOSK_MODEL" in text and "vosk-model-small-en-us" in text
    for path in ("schemas", "services", "pyproject.toml"):
        assert path in text
