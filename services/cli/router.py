"""An embedded Zenoh router: zenoh-python in router mode, listening only where told.

`python -m services.cli.router --port 7447 --keys-dir <keys>` runs a secured one on loopback
(authentication and the access rules generated from `schemas/access.py`) until SIGTERM or Ctrl-C.
Without `--keys-dir` it runs open (anyone who reaches it may do anything), which tests and
benchmarks use; it says so in its log. `--config FILE` runs a full Zenoh configuration instead
(`hri keys router-config` writes one).
"""

from __future__ import annotations

import socket
import time
from pathlib import Path

import typer
import zenoh

from services.runtime import ConfigError, RouterSecurity, get_logger, router_config
from services.runtime.signals import stop_on_signals

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


OPEN_WARNING = ("OPEN BUS: this router asks no credentials and applies no access rules; anyone who "
                "can reach it can make the robot move")


class Router:
    """A router session; `close()` (or the context manager) ends it. With `security`, clients must
    authenticate and the generated access rules apply; without, the bus is open."""

    def __init__(self, listen: list[str], security: RouterSecurity | None = None,
                 config: zenoh.Config | None = None) -> None:
        self.listen = listen
        self.security = security
        self.session = zenoh.open(config if config is not None else router_config(listen, security))

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
        [], help="Explicit listen endpoints instead of loopback (repeatable), e.g. tls/0.0.0.0:7447"
    ),
    keys_dir: Path | None = typer.Option(None, "--keys-dir", help="Secure: the deployment's keys (`hri keys init`)"),
    robot: str = typer.Option("op2", envvar="HRI_ROBOT", help="Robot id the access rules cover"),
    no_operator_writes: bool = typer.Option(False, "--no-operator-writes", help="Withhold the operator's puts"),
    config: Path | None = typer.Option(None, "--config", help="A full Zenoh JSON5 router configuration"),
) -> None:
    """Run a Zenoh router until SIGTERM or Ctrl-C."""
    log = get_logger("router")
    endpoints = listen or [loopback_endpoint(port)]
    stop = stop_on_signals()
    security = RouterSecurity(keys_dir, robot=robot, operator_writes=not no_operator_writes) if keys_dir else None
    try:
        router = Router(endpoints, security, zenoh.Config.from_file(str(config)) if config else None)
    except (ConfigError, zenoh.ZError) as exc:
        log.error("cannot start the router", error=str(exc).splitlines()[0])
        raise typer.Exit(2) from None
    with router:
        if config:
            log.info("router running", config=str(config))
        else:
            log.info("router listening", endpoints=",".join(endpoints), secured=security is not None)
            if security is None:
                log.warning(OPEN_WARNING)
        while not stop.wait(0.5):
            pass
    log.info("router stopped")


if __name__ == "__main__":
    typer.run(main)
