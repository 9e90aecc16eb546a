"""`hri up` end to end: five services alive, probing with hri and zenoh-cli, restarts, clean stops."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from schemas.keys import SERVICES
from services.cli.router import free_port
from tests.conftest import ROOT, service_env, wait_for

ZENOH_CLI = str(Path(sys.executable).with_name("zenoh"))


def hri(*args: str, env: dict[str, str], timeout: float = 30) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "services.cli", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


def status(endpoint: str, env: dict[str, str]) -> dict[str, dict]:
    out = hri("status", "--json", "--connect", endpoint, env=env)
    return json.loads(out.stdout)


def child_pids(endpoint: str, env: dict[str, str]) -> dict[str, int]:
    return {name: row["health"]["detail"]["pid"] for name, row in status(endpoint, env).items()
            if row["health"]}


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.fixture
def launched(robot_id: str, tmp_path: Path) -> Iterator[tuple[subprocess.Popen[bytes], str, dict[str, str]]]:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    env = service_env(endpoint, robot_id, HRI_STATE_DIR=str(tmp_path / "state"),
                      HRI_SPEECH_OUT=str(tmp_path / "speech"), HRI_VISION_SOURCE="synthetic:none",
                      HRI_VOICE_SOURCE=f"watch:{tmp_path / 'spool'}", HRI_MOTION_SIM="1",
                      HRI_KEYS_DIR=str(tmp_path / "keys"))  # `hri up` makes the identities there
    (tmp_path / "spool").mkdir()
    log = open(tmp_path / "up.log", "wb")  # noqa: SIM115
    proc = subprocess.Popen([sys.executable, "-m", "services.cli", "up", "--port", str(port)], cwd=ROOT,
                            env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        wait_for(lambda: all(r["alive"] for r in status(endpoint, env).values()), timeout=60, interval=0.5)
        yield proc, endpoint, env
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            proc.wait(15)
        log.close()


def test_up_probe_and_ctrl_c(launched, robot_id: str) -> None:
    proc, endpoint, env = launched
    rows = status(endpoint, env)
    assert sorted(n for n, r in rows.items() if r["alive"]) == sorted(SERVICES)
    pids = child_pids(endpoint, env)
    assert len(pids) == 5 and all(pid_alive(p) for p in pids.values())

    # A third-party client, as the observer, sees the liveliness tokens ...
    observer = hri("keys", "client-config", "observer", "--connect", endpoint, env=env).stdout.strip()
    operator = hri("keys", "client-config", "operator", "--connect", endpoint, env=env).stdout.strip()
    out = subprocess.run([ZENOH_CLI, "--config", observer, "liveliness", "get",
                          "-k", f"hri/{robot_id}/alive/**"], capture_output=True, text=True, timeout=30)
    assert {json.loads(line)["key"].rsplit("/", 1)[1] for line in out.stdout.splitlines()} == set(SERVICES)

    # ... and the JSON traffic.
    # SIGINT restored for it: the third-party CLI stops only through KeyboardInterrupt, which a suite
    # started from a script's background job (SIGINT ignored, inherited) would never raise.
    sub = subprocess.Popen([ZENOH_CLI, "--config", observer, "subscribe", "-k",
                            f"hri/{robot_id}/voice/**", "--decoder", "json"], stdout=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        time.sleep(1.5)
        hri("send", "command", "yes", "--connect", endpoint, env=env)
        # Garbage on a key the reasoner reads is logged, counted and dropped; nothing exits.
        subprocess.run([ZENOH_CLI, "--config", operator, "put", "-k",
                        f"hri/{robot_id}/voice/command", "-v", "not json"], check=True, timeout=30)
        time.sleep(1.0)
    finally:
        sub.send_signal(signal.SIGINT)
        seen, _ = sub.communicate(timeout=10)
    first = json.loads(seen.splitlines()[0])
    assert first["command"] == "yes" and first["engine"] == "hri-send"
    reasoner = wait_for(lambda: (h := status(endpoint, env)["reasoner"]["health"]) and h["rejected"] >= 1 and h)
    assert reasoner["status"] in ("ok", "degraded")
    assert child_pids(endpoint, env) == pids  # nobody crashed or restarted

    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    assert proc.wait(10) == 0
    wait_for(lambda: not any(pid_alive(p) for p in pids.values()), timeout=5)
    assert time.monotonic() - t0 < 5.0


def test_crashed_service_is_restarted(launched) -> None:
    _proc, endpoint, env = launched
    before = child_pids(endpoint, env)
    os.kill(before["speech"], signal.SIGKILL)
    after = wait_for(lambda: (p := child_pids(endpoint, env)).get("speech") not in (None, before["speech"]) and p,
                     timeout=20, interval=0.3)
    assert {k: v for k, v in after.items() if k != "speech"} == {k: v for k, v in before.items() if k != "speech"}


def test_children_stop_when_the_launcher_is_killed(launched) -> None:
    proc, endpoint, env = launched
    pids = child_pids(endpoint, env)
    proc.kill()
    proc.wait(5)
    wait_for(lambda: not any(pid_alive(p) for p in pids.values()), timeout=10)


def test_up_connect_joins_an_existing_router(router_endpoint: str, robot_id: str, tmp_path: Path) -> None:
    env = service_env(router_endpoint, robot_id, HRI_SPEECH_OUT=str(tmp_path))
    proc = subprocess.Popen([sys.executable, "-m", "services.cli", "up", "--connect", router_endpoint,
                             "--only", "speech"], cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        wait_for(lambda: status(router_endpoint, env)["speech"]["alive"], timeout=30, interval=0.3)
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(10) == 0


def test_unknown_service_is_refused() -> None:
    out = hri("up", "--only", "dance", env=dict(os.environ))
    assert out.returncode != 0 and "unknown service" in out.stderr


def test_a_bad_log_level_is_refused_before_anything_starts() -> None:
    out = hri("up", "--open", "--port", str(free_port()), env={**os.environ, "HRI_LOG_LEVEL": "loud"})
    assert out.returncode == 2
    assert "HRI_LOG_LEVEL='loud'" in out.stderr and "started" not in out.stderr
