"""Probing tools for people at a terminal: `hri spy`, `hri status`, `hri send`."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import datetime

import zenoh
from pydantic import BaseModel
from rich.console import Console
from rich.table import Table

from schemas.access import OBSERVER
from schemas.keys import SERVICES, Keys
from schemas.messages import Header, Health, HealthStatus
from services.cli.backlog import Backlog
from services.runtime import (
    BusSettings,
    DecodeError,
    SessionRefused,
    decode,
    encode,
    encoding_for,
    open_session,
)
from services.runtime.logs import get_logger


class BusUnreachable(RuntimeError):
    """No Zenoh router answered where the settings point; the message says where that was."""


@contextmanager
def client_session(robot: str | None, connect: str | None,
                   identity: str = OBSERVER) -> Iterator[tuple[zenoh.Session, Keys]]:
    """A client session on the robot's bus as `identity` (`HRI_CREDENTIALS`, else
    `<keys dir>/<identity>` when it exists). Raises `ConfigError` for bad settings, `BusUnreachable`
    when no router answers, `SessionRefused` when a router refuses this identity."""
    settings = BusSettings.from_env(robot=robot, connect=connect, identity=identity)
    try:
        session = open_session(settings, get_logger("hri"), attempts=3)
    except SessionRefused as exc:
        if exc.refused:
            raise
        raise BusUnreachable(f"no Zenoh router answers at {','.join(settings.connect)}") from None
    except zenoh.ZError:
        where = f"ZENOH_CONFIG={settings.config_file}" if settings.config_file else ",".join(settings.connect)
        raise BusUnreachable(f"no Zenoh router answers at {where}") from None
    try:
        yield session, Keys(settings.robot)
    finally:
        session.close()


# ---------------------------------------------------------------------------------------- status
def alive_services(session: zenoh.Session, keys: Keys, timeout: float = 2.0, service: str | None = None) -> set[str]:
    """The services (or only `service`) whose liveliness tokens are on the robot's bus now."""
    return {
        keys.service_of_alive(str(reply.ok.key_expr))
        for reply in session.liveliness().get(keys.alive(service) if service else keys.alive_all, timeout=timeout)
        if reply.ok is not None
    }


def gather_status(session: zenoh.Session, keys: Keys, timeout: float = 2.0,
                  service: str | None = None) -> dict[str, dict[str, object]]:
    """Liveliness and health of every service seen on the bus (and the five expected ones), or of one."""
    names = [service] if service else SERVICES
    rows: dict[str, dict[str, object]] = {name: {"alive": False, "health": None} for name in names}
    for name in alive_services(session, keys, timeout, service):
        rows.setdefault(name, {"health": None})["alive"] = True
    for reply in session.get(keys.health(service) if service else keys.health_all, timeout=timeout):
        if reply.ok is None:
            continue
        try:
            health = decode(reply.ok.payload.to_bytes(), Health)
        except DecodeError:
            continue
        rows.setdefault(health.service, {"alive": False})["health"] = health
    return rows


_STYLE = {HealthStatus.OK: "green", HealthStatus.DEGRADED: "yellow", HealthStatus.FAILED: "red"}


def status_table(rows: dict[str, dict[str, object]], robot: str) -> Table:
    table = Table(title=f"hri/{robot}")
    for col in ("service", "alive", "status", "uptime s", "received", "published", "rejected"):
        table.add_column(col, justify="right" if col in ("uptime s", "received", "published", "rejected") else "left")
    table.add_column("detail", overflow="fold")  # wrapped between entries, never cut: every value whole
    for name, row in rows.items():
        health = row.get("health")
        alive = "[green]yes[/]" if row.get("alive") else "[red]no[/]"
        if isinstance(health, Health):
            detail = ", ".join(f"{k}={v}" for k, v in health.detail.items())
            table.add_row(name, alive, f"[{_STYLE[health.status]}]{health.status.value}[/]",
                          f"{health.uptime_s:.1f}", str(health.received), str(health.published),
                          str(health.rejected), detail)
        else:
            table.add_row(name, alive, "-", "-", "-", "-", "-", "")
    return table


# ---------------------------------------------------------------------------------------- spy
def format_sample(sample: zenoh.Sample, prefix: str) -> str:
    key = str(sample.key_expr)
    short = key[len(prefix) + 1:] if key.startswith(prefix + "/") else key
    stamp = datetime.now().strftime("%H:%M:%S.%f")[:-3]
    schema = str(sample.encoding)
    raw = sample.payload.to_bytes()
    try:
        body = json.dumps(json.loads(raw), separators=(",", ":"))
    except (ValueError, UnicodeDecodeError):
        body = repr(raw[:200])
    return f"{stamp} {short:<22} {schema:<32} {body}"


SPY_BACKLOG = 10_000  # lines waiting for a paused terminal, at most (then dropped, counted)


def spy(session: zenoh.Session, keyexpr: str, prefix: str, console: Console, stop: threading.Event) -> None:
    """Print the traffic until `stop`. Zenoh's callbacks only format and hand over: a paused terminal must not stop
    this client from reading the bus (`backlog.py`)."""

    def show(line: str) -> None:
        console.print(line, markup=False, highlight=False, soft_wrap=True)

    def dropped(n: int) -> None:
        show(f"... {n} line(s) not shown: the output was paused")

    shown: Backlog[str] = Backlog(show, dropped, capacity=SPY_BACKLOG, name="spy-output")

    def on_sample(sample: zenoh.Sample) -> None:
        shown.put(format_sample(sample, prefix))

    def on_alive(sample: zenoh.Sample) -> None:
        sign = "+ alive" if sample.kind == zenoh.SampleKind.PUT else "- gone "
        shown.put(f"{datetime.now():%H:%M:%S.%f}"[:-3] + f" {sign} {sample.key_expr}")

    sub = session.declare_subscriber(keyexpr, on_sample)
    live = session.liveliness().declare_subscriber(f"{prefix}/alive/**", on_alive, history=True)
    try:
        while not stop.wait(0.2):
            pass
    finally:
        sub.undeclare()
        live.undeclare()
        shown.close()


# ---------------------------------------------------------------------------------------- send
def publish_once(session: zenoh.Session, key: str, msg: Header, wait_s: float = 1.0) -> BaseModel:
    """Publish one message as a service would, after waiting briefly for a subscriber to match."""
    pub = session.declare_publisher(key, encoding=encoding_for(type(msg)))
    deadline = time.monotonic() + wait_s
    while not pub.matching_status and time.monotonic() < deadline:
        time.sleep(0.02)
    msg.stamp, msg.seq = time.time(), 1
    pub.put(encode(msg))
    time.sleep(0.05)  # let the sample leave before the session closes
    pub.undeclare()
    return msg
