"""One service under test, alone on a bus: a Zenoh router process, the service as a process and a
session of one's own on that bus. The per-service benchmarks measure through this; the whole robot
is `simrobot.py`."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import IO

import zenoh

from schemas.keys import Keys
from services.cli.router import free_port, loopback_endpoint, wait_listening
from services.runtime import ServiceContext, client_config

Output = IO[bytes] | int | None
"""Where a process's output goes: a file, `subprocess.DEVNULL`, or None for this terminal."""


@dataclass
class Rig:
    robot: str
    endpoint: str
    env: dict[str, str]
    """The services' environment: this process's, pointed at the rig's router and robot."""
    ctx: ServiceContext
    procs: list[subprocess.Popen[bytes]] = field(default_factory=list)

    def start(self, service: str, output: Output = subprocess.DEVNULL, stdin: Output = None) -> subprocess.Popen[bytes]:
        """Start `python -m services.<service>` on the rig's bus (`stdin`: `subprocess.PIPE` for a stream written to
        it); it is stopped with the rig."""
        proc = subprocess.Popen([sys.executable, "-m", f"services.{service}"], env=self.env, stdin=stdin,
                                stdout=output, stderr=None if output is None else subprocess.STDOUT)
        self.procs.append(proc)
        return proc


@contextmanager
def service_rig(robot: str, participant: str = "bench", **env: str) -> Iterator[Rig]:
    """A router on a free loopback port and a session on it; `env` adds service settings. On exit the
    session closes and every process gets SIGTERM (SIGKILL if it is still there 15 s later)."""
    port = free_port()
    endpoint = loopback_endpoint(port)
    service_env = {**os.environ, "HRI_ZENOH_CONNECT": endpoint, "HRI_ROBOT": robot, **env}
    service_env.pop("ZENOH_CONFIG", None)  # it would win over HRI_ZENOH_CONNECT
    router = subprocess.Popen([sys.executable, "-m", "services.cli.router", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [router]
    try:
        wait_listening(port)
        ctx = ServiceContext(participant, zenoh.open(client_config([endpoint])), Keys(robot))
        rig = Rig(robot, endpoint, service_env, ctx, procs)
        try:
            yield rig
        finally:
            ctx.close()
    finally:
        for proc in reversed(procs):
            proc.send_signal(signal.SIGTERM)
        for proc in reversed(procs):
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
