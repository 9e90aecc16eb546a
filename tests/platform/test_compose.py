"""docker-compose.yml, the Dockerfile and their helpers, checked for structure; `tools/compose-check` runs
the stack itself on a Docker engine (and `.ci/run` runs that where an engine can start)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import yaml

from schemas.keys import SERVICES

ROOT = Path(__file__).resolve().parents[2]
COMPOSE = yaml.safe_load((ROOT / "docker-compose.yml").read_text())


def test_router_is_the_projects_own_with_the_generated_rules_on_tls_only() -> None:
    zenoh = COMPOSE["services"]["zenoh"]
    assert zenoh["image"] == "${HRI_IMAGE:-hri-op2:latest}" and zenoh["pull_policy"] == "never"
    cmd = zenoh["command"]
    assert cmd[:3] == ["python", "-m", "services.cli.router"]
    assert cmd[cmd.index("--keys-dir") + 1] == "/run/secrets/hri"
    assert cmd[cmd.index("--listen") + 1] == "tls/0.0.0.0:7447"  # never plain TCP off loopback
    assert cmd[cmd.index("--robot") + 1] == "${HRI_ROBOT:-op2}"
    assert zenoh["volumes"] == ["${HRI_KEYS_DIR:-./keys}/router:/run/secrets/hri/router:ro",
                                "hri-state:/var/lib/hri:ro"]
    # published on loopback unless asked otherwise, and no REST plugin (it would bypass the rules)
    assert zenoh["ports"] == ["${HRI_PUBLISH_ADDR:-127.0.0.1}:${HRI_ROUTER_PORT:-7447}:7447"]


def test_every_service_runs_an_importable_module_as_itself_against_the_router() -> None:
    assert set(COMPOSE["services"]) == {"zenoh", *SERVICES}
    for name in SERVICES:
        svc = COMPOSE["services"][name]
        cmd = svc["command"]
        assert cmd[:2] == ["python", "-m"], cmd
        assert cmd[2] == f"services.{name}"
        assert importlib.util.find_spec(cmd[2]) is not None, cmd[2]
        assert importlib.util.find_spec(f"{cmd[2]}.__main__") is not None
        assert svc["environment"]["HRI_ZENOH_CONNECT"] == "tls/zenoh:7447"
        assert svc["environment"]["HRI_CREDENTIALS"] == "/run/secrets/hri"
        # only its own secrets, read-only
        assert f"${{HRI_KEYS_DIR:-./keys}}/{name}:/run/secrets/hri:ro" in svc["volumes"]
        assert [v for v in svc["volumes"] if "/run/secrets" in v] == [
            f"${{HRI_KEYS_DIR:-./keys}}/{name}:/run/secrets/hri:ro"]
        assert "zenoh" in svc["depends_on"] and svc["image"] == "${HRI_IMAGE:-hri-op2:latest}"


def test_the_compose_routers_configuration_builds_from_fresh_secrets(tmp_path: Path) -> None:
    """What the router container runs, here: identities from `hri keys init`, the generated rules."""
    from services.cli import keys as deployment_keys
    from services.runtime import RouterSecurity, router_config

    deployment_keys.init(tmp_path / "keys")
    router_config(["tls/0.0.0.0:7447"], RouterSecurity(tmp_path / "keys", robot="op2"))


def test_one_image_is_built_once_for_the_five_services() -> None:
    builders = [name for name, svc in COMPOSE["services"].items() if "build" in svc]
    assert builders == ["vision"] and COMPOSE["services"]["vision"]["build"] == "."
    for name in SERVICES:
        if name != "vision":
            assert COMPOSE["services"][name]["pull_policy"] == "never"  # the image is local, never pulled


def test_every_service_has_a_health_check_on_its_own_health() -> None:
    for name in SERVICES:
        check = COMPOSE["services"][name]["healthcheck"]
        assert check["test"] == ["CMD", "hri", "status", "--service", name]
        assert check["start_period"] and check["interval"]


def test_the_synthetic_camera_shows_nothing_until_told() -> None:
    assert COMPOSE["services"]["vision"]["environment"]["HRI_VISION_SOURCE"] == "${HRI_VISION_SOURCE:-synthetic:none}"


def test_the_voice_engine_is_the_services_own_default_unless_set() -> None:
    """No pinned engine: the scenarios expect what the voice service recognises by default."""
    environment = COMPOSE["services"]["voice"]["environment"]
    assert "HRI_VOICE_ENGINE" in environment and environment["HRI_VOICE_ENGINE"] is None  # passed through
    assert "HRI_VOICE_VAD" in environment and environment["HRI_VOICE_VAD"] is None  # so is the microphone's VAD


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
    assert "espeak-ng" in text and 'pip install --no-cache-dir --no-deps ".[mic]"' in text
    assert "HRI_VOSK_MODEL" in text and "vosk-model-small-en-us" in text
    for path in ("schemas", "services", "pyproject.toml"):
        assert path in text


def test_the_vosk_model_is_checksummed_and_its_url_overridable() -> None:
    text = (ROOT / "Dockerfile").read_text()
    assert re.search(r"^ARG VOSK_MODEL_URL=https://\S+\.zip$", text, re.M)
    assert re.search(r"^ARG VOSK_MODEL_SHA256=[0-9a-f]{64}$", text, re.M)
    assert 'fetch-model.py "$VOSK_MODEL_URL" "$VOSK_MODEL_SHA256"' in text


def test_services_run_as_a_user_with_the_state_folders_made() -> None:
    text = (ROOT / "Dockerfile").read_text()
    users = re.findall(r"^USER (\S+)$", text, re.M)
    assert users and users[-1] not in ("root", "0")
    assert "/var/lib/hri/voice-spool" in text  # a fresh volume gets it, so voice is not degraded
    voice_source = COMPOSE["services"]["voice"]["environment"]["HRI_VOICE_SOURCE"]
    assert voice_source.endswith("watch:/var/lib/hri/voice-spool}")


def test_the_build_context_is_only_what_the_image_needs() -> None:
    ignore = (ROOT / ".dockerignore").read_text().splitlines()
    assert ignore[1] == "*"  # everything out, then only these back in
    allowed = {line[1:] for line in ignore if line.startswith("!")}
    copied = set(re.findall(r"^COPY (.+) \S+$", (ROOT / "Dockerfile").read_text(), re.M))
    assert {p for c in copied for p in c.split()} <= allowed


def test_the_open_classroom_override_is_explicit() -> None:
    """docker-compose.open.yml: the router without --keys-dir (it warns OPEN BUS), plain TCP, and the
    services without credentials; nothing else changes."""
    override = yaml.safe_load((ROOT / "docker-compose.open.yml").read_text())
    cmd = override["services"]["zenoh"]["command"]
    assert cmd[:3] == ["python", "-m", "services.cli.router"] and "--keys-dir" not in cmd
    for name in SERVICES:
        assert override["services"][name]["environment"] == {"HRI_ZENOH_CONNECT": "tcp/zenoh:7447",
                                                              "HRI_CREDENTIALS": ""}
    assert "OPEN BUS" in (ROOT / "docker-compose.open.yml").read_text()


def test_the_state_volume_is_filled_once_by_the_router_before_the_services_are_made() -> None:
    """Docker copies the image's /var/lib/hri into the empty volume when the first container using it is
    created; five services created in parallel can race on that copy (seen once in CI: "mkdir
    .../_data/speech: file exists"). The router, which all of them wait for, mounts it first, read-only."""
    assert "hri-state:/var/lib/hri:ro" in COMPOSE["services"]["zenoh"]["volumes"]
    for name in SERVICES:
        svc = COMPOSE["services"][name]
        assert "hri-state:/var/lib/hri" in svc["volumes"] and "zenoh" in svc["depends_on"]
