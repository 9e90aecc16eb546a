"""`hri status`, `spy`, `send` with no router, and `hri up` on a port in use: one line, a hint, non-zero."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from services.cli.router import free_port
from tests.conftest import ROOT


def hri(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("HRI_", "ZENOH_"))}
    return subprocess.run([sys.executable, "-m", "services.cli", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=timeout, env=env)


@pytest.mark.parametrize("args", [["status"], ["status", "--service", "voice"], ["spy"],
                                  ["send", "command", "go"]])
def test_no_router_is_one_line_with_a_hint(args: list[str]) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"  # nothing listens there
    out = hri(*args, "--connect", endpoint)
    assert out.returncode == 1
    assert out.stdout == "" and out.stderr.count("\n") == 1, out.stderr
    assert out.stderr.startswith(f"error: no Zenoh router answers at {endpoint}")
    assert "hri up" in out.stderr and "--connect" in out.stderr


def test_invalid_settings_exit_2_in_one_line() -> None:
    out = hri("status", "--robot", "a/b")
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "invalid robot id" in out.stderr


def test_up_on_a_port_in_use_says_so_in_one_line(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        # the deployment's identities are made in the test's folder, not the user's
        out = hri("up", "--port", str(port), "--no-restart", "--keys-dir", str(tmp_path / "keys"))
    assert out.returncode == 1
    assert "Traceback" not in out.stderr + out.stdout
    errors = [line for line in out.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "the port is in use" in errors[0]
    assert "--port" in errors[0] and f"--connect tcp/127.0.0.1:{port}" in errors[0]
