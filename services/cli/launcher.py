"""`hri up`: an embedded Zenoh router plus the five services as supervised child processes.

Children are started with `subprocess` (fork immediately followed by exec, the equivalent of
multiprocessing's spawn start method): nothing of this process's Zenoh session is inherited, which
would hang the child (REFERENCE.md). Each child learns the launcher's pid (`HRI_LAUNCHER_PID`) and
stops by itself if the launcher disappears, even after a SIGKILL, so no orphan outlives it.

With `keys_dir` (what `hri up` passes unless told `--open`), the embedded router requires
authentication and applies the generated access rules, and each child runs as its own identity
(`HRI_CREDENTIALS=<keys_dir>/<service>`).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from schemas.keys import SERVICES
from services.cli.backlog import Backlog
from services.cli.router import OPEN_WARNING, Router, loopback_endpoint
from services.runtime import PARENT_ENV, RouterSecurity, get_logger
from services.runtime.config import CREDENTIALS_ENV
from services.runtime.signals import stop_on_signals

LineSink = Callable[[str, str], None]
"""Receives (service name, one line of its output)."""

STOP_GRACE_S = 4.0
LINE_BACKLOG = 10_000  # the children's lines waiting for a slow output, at most (then dropped, counted)
BACKOFF_START_S = 0.5
BACKOFF_MAX_S = 10.0
STABLE_AFTER_S = 30.0


@dataclass
class Child:
    name: str
    argv: list[str]
    env: dict[str, str]
    proc: subprocess.Popen[bytes] | None = None
    started_at: float = 0.0
    restarts: int = 0
    failures_in_a_row: int = 0
    next_start: float = 0.0
    reader: threading.Thread | None = field(default=None, repr=False)


class Launcher:
    """Starts, supervises and stops the services. Usable from code (demo, system tests) and `hri up`."""

    def __init__(
        self,
        services: Sequence[str] = SERVICES,
        *,
        port: int = 7447,
        connect: str | None = None,
        robot: str | None = None,
        env: Mapping[str, str] | None = None,
        service_env: Mapping[str, Mapping[str, str]] | None = None,
        sink: LineSink | None = None,
        restart: bool = True,
        keys_dir: Path | None = None,
        operator_writes: bool = True,
        listen: Sequence[str] = (),
    ) -> None:
        unknown = set(services) - set(SERVICES)
        if unknown:
            raise ValueError(f"unknown service(s) {sorted(unknown)}; choose from {', '.join(SERVICES)}")
        self.log = get_logger("launcher")
        self.endpoint = connect or loopback_endpoint(port)
        self._embedded = connect is None
        self._router: Router | None = None
        self._sink = sink or _print_line
        self._lines: Backlog[tuple[str, str]] | None = None
        self._restart = restart
        self._stopping = threading.Event()
        self._lock = threading.Lock()
        self._supervisor: threading.Thread | None = None
        self.keys_dir = keys_dir
        self.listen = [self.endpoint, *listen]  # the children use the first (loopback)
        self.security = (RouterSecurity(keys_dir, robot=robot or os.environ.get("HRI_ROBOT") or "op2",
                                        operator_writes=operator_writes) if keys_dir is not None else None)
        base = dict(os.environ)
        base.pop("ZENOH_CONFIG", None)  # the launcher decides where children connect
        base.pop(CREDENTIALS_ENV, None)  # and who each child is
        base.update(env or {})
        base.update(HRI_ZENOH_CONNECT=self.endpoint, PYTHONUNBUFFERED="1", **{PARENT_ENV: str(os.getpid())})
        if robot:
            base["HRI_ROBOT"] = robot
        self.children: dict[str, Child] = {
            name: Child(name, [sys.executable, "-m", f"services.{name}"],
                        {**base, **self._identity_env(name), **dict((service_env or {}).get(name, {}))})
            for name in services
        }

    def _identity_env(self, name: str) -> dict[str, str]:
        return {CREDENTIALS_ENV: str(self.keys_dir / name)} if self.keys_dir is not None else {}

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        if self._embedded:
            self._router = Router(self.listen, self.security)
            self.log.info("router listening", endpoints=",".join(self.listen), secured=self.security is not None,
                          keys_dir=str(self.keys_dir) if self.keys_dir else None)
            if self.security is None:
                self.log.warning(OPEN_WARNING)
        else:
            self.log.info("joining existing router", endpoint=self.endpoint)
        self._lines = self._backlog()
        for child in self.children.values():
            self._spawn(child)
        self._supervisor = threading.Thread(target=self._supervise, name="supervisor", daemon=True)
        self._supervisor.start()

    def stop(self, grace_s: float = STOP_GRACE_S) -> None:
        """SIGTERM every child, SIGKILL what is left after `grace_s`, then close the router."""
        self._stopping.set()
        if self._supervisor is not None:
            self._supervisor.join(2.0)
        with self._lock:
            procs = [c.proc for c in self.children.values() if c.proc and c.proc.poll() is None]
        for proc in procs:
            _signal(proc, signal.SIGTERM)
        deadline = time.monotonic() + grace_s
        for proc in procs:
            try:
                proc.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self.log.warning("child ignored SIGTERM, killing", pid=proc.pid)
                _signal(proc, signal.SIGKILL)
                proc.wait(2.0)
        for child in self.children.values():
            if child.reader is not None:
                child.reader.join(1.0)
        if self._lines is not None:
            self._lines.close()
            self._lines = None
        if self._router is not None:
            self._router.close()
            self._router = None
        self.log.info("all stopped")

    def __enter__(self) -> Launcher:
        self.start()
        return self

    def __exit__(self, *_exc: object) -> None:
        self.stop()

    def pid(self, name: str) -> int | None:
        proc = self.children[name].proc
        return proc.pid if proc and proc.poll() is None else None

    def restarts(self, name: str) -> int:
        return self.children[name].restarts

    # ------------------------------------------------------------------ internals
    def _spawn(self, child: Child) -> None:
        proc = subprocess.Popen(
            child.argv,
            env=child.env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            # Own process group: a terminal's Ctrl-C reaches the launcher only, which then stops
            # the children in order instead of racing them (and restarting them) on the way down.
            start_new_session=True,
        )
        with self._lock:
            child.proc = proc
            child.started_at = time.monotonic()
        child.reader = threading.Thread(
            target=self._pump, args=(child.name, proc.stdout), name=f"log:{child.name}", daemon=True
        )
        child.reader.start()
        self.log.info("started", child=child.name, pid=proc.pid)

    def _backlog(self) -> Backlog[tuple[str, str]]:
        """The children's lines on their way to the sink: reading them never waits for it (`backlog.py`)."""
        sink = self._sink

        def dropped(n: int) -> None:
            sink("launcher", f"{n} line(s) of the services' output dropped: it was not being read")

        return Backlog(lambda item: sink(*item), dropped, capacity=LINE_BACKLOG, name="log-lines")

    def _pump(self, name: str, stream: IO[bytes] | None) -> None:
        lines = self._lines
        if stream is None or lines is None:
            return
        for raw in iter(stream.readline, b""):
            lines.put((name, raw.decode("utf-8", "replace").rstrip("\n")))
        stream.close()

    def _supervise(self) -> None:
        while not self._stopping.wait(0.1):
            now = time.monotonic()
            for child in self.children.values():
                proc = child.proc
                if proc is None:
                    if now >= child.next_start and not self._stopping.is_set():
                        child.restarts += 1
                        self._spawn(child)
                    continue
                code = proc.poll()
                if code is None:
                    if now - child.started_at > STABLE_AFTER_S:
                        child.failures_in_a_row = 0
                    continue
                if not self._restart:
                    continue
                delay = min(BACKOFF_START_S * 2**child.failures_in_a_row, BACKOFF_MAX_S)
                child.failures_in_a_row += 1
                child.next_start = now + delay
                self.log.warning("child exited, restarting", child=child.name, code=code, retry_in_s=delay)
                with self._lock:
                    child.proc = None


def _signal(proc: subprocess.Popen[bytes], sig: signal.Signals) -> None:
    try:
        proc.send_signal(sig)
    except ProcessLookupError:
        pass


_WIDTH = max(len(s) for s in SERVICES)
_print_lock = threading.Lock()


def _print_line(name: str, line: str) -> None:
    with _print_lock:
        sys.stdout.write(f"{name:<{_WIDTH}} | {line}\n")
        sys.stdout.flush()


def run_until_signalled(launcher: Launcher, ready: Callable[[], None] | None = None) -> int:
    """Start `launcher`, wait for SIGTERM or Ctrl-C, stop everything. Returns the exit code."""
    stop = stop_on_signals()
    try:
        launcher.start()
        if ready:
            ready()
        while not stop.wait(0.5):
            pass
    finally:
        launcher.stop()
    return 0
