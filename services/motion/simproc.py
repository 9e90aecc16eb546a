"""The simulated OP2 bus as a child process of the motion service (`python -m services.motion.simbus`).

A separate process keeps the simulator off the service's GIL, as real servos would be. It is
started with subprocess, whose fork is followed at once by exec: like multiprocessing's spawn start
method, the child inherits nothing of the service's Zenoh session (a plain fork would hang it). It
watches its parent, and is restarted if it dies.
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

from services.motion.driver import BusError

ROOT = Path(__file__).resolve().parents[2]


class SimProcess:
    def __init__(self, log: Any, *, start_timeout_s: float = 15.0) -> None:
        self.log = log
        self.start_timeout_s = start_timeout_s
        self._proc: subprocess.Popen[bytes] | None = None
        self._path: str | None = None

    @property
    def pid(self) -> int | None:
        return self._proc.pid if self._proc is not None else None

    def port(self) -> str:
        """The pty of a running simulator, starting (or restarting) it when needed."""
        if self._proc is not None and self._proc.poll() is None and self._path:
            return self._path
        if self._proc is not None:
            self.log.warning("simulated bus exited, restarting", returncode=self._proc.returncode)
        return self._start()

    def _start(self) -> str:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "services.motion.simbus", "--parent-pid", str(os.getpid())],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
        )
        assert self._proc.stdout is not None
        ready, _, _ = select.select([self._proc.stdout], [], [], self.start_timeout_s)
        line = self._proc.stdout.readline().decode().strip() if ready else ""
        if not line.startswith("/dev/"):
            self.stop()
            raise BusError(
                f"the simulated OP2 bus did not start (no device path within {self.start_timeout_s} s)"
            )
        self._path = line
        self.log.info("simulated OP2 bus started", device=line, pid=self._proc.pid)
        return line

    def stop(self) -> None:
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(3)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(3)
        if proc.stdout is not None:
            proc.stdout.close()
