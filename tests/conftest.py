"""Shared fixtures: a real Zenoh router per test session, a unique robot id per test (so tests
sharing the router never see each other's traffic), and service processes started as users would."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from queue import Queue

import pytest
import zenoh

from schemas.keys import Keys
from services.cli import probe
from services.cli.router import free_port, wait_listening
from services.runtime import ServiceContext, client_config

ROOT = Path(__file__).resolve().parents[1]


def wait_for(predicate: Callable[[], object], timeout: float = 10.0, interval: float = 0.02) -> object:
    """Poll `predicate` until it returns something truthy; fail the test after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"condition not met within {timeout} s: {predicate}")
        time.sleep(interval)


@pytest.fixture(scope="session", autouse=True)
def state_home(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Every test and every process it starts keeps its state (the speech WAVs, a reasoner's latched
    danger, keys made by default) in a folder of the session, never in the user's ~/.local/state."""
    home = tmp_path_factory.mktemp("state-home")
    saved = {name: os.environ.pop(name, None) for name in ("XDG_STATE_HOME", "HRI_STATE_DIR")}
    os.environ["XDG_STATE_HOME"] = str(home)
    try:
        yield home
    finally:
        os.environ.pop("XDG_STATE_HOME", None)
        os.environ.update({name: value for name, value in saved.items() if value is not None})


@pytest.fixture(scope="session")
def router_endpoint() -> Iterator[str]:
    """A zenoh-python router on a free loopback port, in its own process."""
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "services.cli.router", "--port", str(port)],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        wait_listening(port)
        yield f"tcp/127.0.0.1:{port}"
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()


@pytest.fixture
def robot_id() -> str:
    return f"t{uuid.uuid4().hex[:10]}"


@pytest.fixture
def keys(robot_id: str) -> Keys:
    return Keys(robot_id)


@pytest.fixture
def bus(router_endpoint: str, keys: Keys) -> Iterator[ServiceContext]:
    """A test-side participant on the bus (service name `tester`), closed after the test."""
    ctx = ServiceContext("tester", zenoh.open(client_config([router_endpoint])), keys)
    try:
        yield ctx
    finally:
        ctx.close()


def service_env(router_endpoint: str, robot_id: str, **extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("ZENOH_CONFIG", None)
    env.update(HRI_ZENOH_CONNECT=router_endpoint, HRI_ROBOT=robot_id, PYTHONUNBUFFERED="1")
    env.update(extra)
    return env


@pytest.fixture
def start_service(
    router_endpoint: str, robot_id: str, tmp_path: Path
) -> Iterator[Callable[..., subprocess.Popen[bytes]]]:
    """`start_service("vision", "--opt", env={...})` runs `python -m services.vision` on the test bus.

    Its combined output goes to `tmp_path/<name>.log`; every process is stopped at teardown.
    """
    procs: list[subprocess.Popen[bytes]] = []

    def start(name: str, *args: str, env: dict[str, str] | None = None) -> subprocess.Popen[bytes]:
        log = open(tmp_path / f"{name}.log", "ab")  # noqa: SIM115 - closed with the process
        proc = subprocess.Popen(
            [sys.executable, "-m", f"services.{name}", *args],
            cwd=ROOT,
            env=service_env(router_endpoint, robot_id, HRI_STATE_DIR=str(tmp_path / "state"), **(env or {})),
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        proc.log_path = tmp_path / f"{name}.log"  # type: ignore[attr-defined]
        procs.append(proc)
        return proc

    yield start
    for proc in procs:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
    for proc in procs:
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()


def read_lines(proc: subprocess.Popen[str], stream: str = "stdout") -> tuple[Queue[str], threading.Thread]:
    """`proc`'s output lines as they come, read by a daemon thread (join it after the process ends)."""
    lines: Queue[str] = Queue()
    pipe = getattr(proc, stream)
    reader = threading.Thread(target=lambda: [lines.put(line) for line in pipe or ()], daemon=True)
    reader.start()
    return lines, reader


def alive_services(ctx: ServiceContext) -> set[str]:
    """Names of the services whose liveliness tokens are on the bus now."""
    return probe.alive_services(ctx.session, ctx.keys)
