"""An embedded Zenoh router: zenoh-python in router mode, listening only where told.

`python -m services.cli.router --port 7447` runs one on loopback until SIGTERM or Ctrl-C.
"""

from __future__ import annotations

import signal
import socket
import threading
import time
from types import FrameType

import typer
import zenoh

from services.runtime import get_logger, router_config

DEFAULT_PORT = 7447


def loopback_endpoint(port: int) -> str:
    return f"tcp/127.0.0.1:{port}"


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nobody listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_listening(port: int, timeout: float = 15.0) -> None:
    """Block until something accepts connections on 127.0.0.1:`port` (a router coming up)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.05)
    raise RuntimeError(f"nothing listens on 127.0.0.1:{port} after {timeout:g} s")


class Router:
    """A router session; `close()` (or the context manager) ends it."""

    def __init__(self, listen: list[str]) -> None:
        self.listen = listen
        self.session = zenoh.open(router_config(listen))

    def close(self) -> None:
        if not self.session.is_closed():
            self.session.close()

    def __enter__(self) -> Router:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


def main(
    port: int = typer.Option(DEFAULT_PORT, help="TCP port on 127.0.0.1"),
    listen: list[str] = typer.Option(
        [], help="Explicit listen endpoints instead of loopback (repeatable), e.g. tcp/0.0.0.0:7447"
    ),
) -> None:
    """Run a Zenoh router until SIGTERM or Ctrl-C."""
    log = get_logger("router")
    endpoints = listen or [loopback_endpoint(port)]
    stop = threading.Event()

    def on_signal(_signum: int, _frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    with Router(endpoints):
        log.info("router listening", endpoints=",".join(endpoints))
        while not stop.wait(0.5):
            pass
    log.info("router stopped")


if __name__ == "__main__":
    typer.run(main)
