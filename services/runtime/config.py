"""Zenoh session configuration and robot id, from the environment (DESIGN.md, Configuration)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import zenoh

from schemas.keys import validate_robot_id

DEFAULT_CONNECT = "tcp/127.0.0.1:7447"
DEFAULT_ROBOT = "op2"


class ConfigError(ValueError):
    """A configuration value is unusable; the message says which and how to fix it."""


@dataclass(frozen=True)
class BusSettings:
    """Where a service joins the bus: a zenoh config file, or client endpoints."""

    robot: str = DEFAULT_ROBOT
    config_file: Path | None = None
    connect: tuple[str, ...] = (DEFAULT_CONNECT,)

    @classmethod
    def from_env(cls, *, robot: str | None = None, connect: str | None = None) -> BusSettings:
        """`ZENOH_CONFIG` wins over `HRI_ZENOH_CONNECT`; explicit arguments win over both."""
        robot = robot or os.environ.get("HRI_ROBOT") or DEFAULT_ROBOT
        try:
            validate_robot_id(robot)
        except ValueError as exc:
            raise ConfigError(f"HRI_ROBOT: {exc}") from None
        config_file = None
        if connect is None and os.environ.get("ZENOH_CONFIG"):
            config_file = Path(os.environ["ZENOH_CONFIG"])
            if not config_file.is_file():
                raise ConfigError(
                    f"ZENOH_CONFIG={config_file} is not a file; point it at a zenoh JSON5 config "
                    "or unset it and use HRI_ZENOH_CONNECT"
                )
        raw = connect or os.environ.get("HRI_ZENOH_CONNECT") or DEFAULT_CONNECT
        endpoints = parse_endpoints(raw)
        return cls(robot=robot, config_file=config_file, connect=endpoints)

    def zenoh_config(self) -> zenoh.Config:
        if self.config_file is not None:
            return zenoh.Config.from_file(str(self.config_file))
        return client_config(self.connect)


def parse_endpoints(raw: str) -> tuple[str, ...]:
    endpoints = tuple(e.strip() for e in raw.split(",") if e.strip())
    if not endpoints:
        raise ConfigError("HRI_ZENOH_CONNECT is empty; give endpoints such as tcp/127.0.0.1:7447")
    for e in endpoints:
        if "/" not in e:
            raise ConfigError(
                f"endpoint {e!r} has no protocol; write it as <proto>/<address>, e.g. tcp/127.0.0.1:7447"
            )
    return endpoints


def client_config(endpoints: tuple[str, ...] | list[str]) -> zenoh.Config:
    """Client mode on explicit endpoints, multicast scouting off (sandboxes and containers block it)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps("client"))
    conf.insert_json5("connect/endpoints", json.dumps(list(endpoints)))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return conf


def router_config(listen: list[str]) -> zenoh.Config:
    """A zenoh-python router listening only where told (the defaults listen on all interfaces)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps("router"))
    conf.insert_json5("listen/endpoints", json.dumps(listen))
    conf.insert_json5("connect/endpoints", "[]")
    conf.insert_json5("scouting/multicast/enabled", "false")
    return conf
