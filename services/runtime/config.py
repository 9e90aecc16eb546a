"""Zenoh session configuration and robot id, from the environment (DESIGN.md, Configuration).

Credentials: an identity is a folder written by `hri keys init` (`<keys>/<identity>/`) holding
`user`, `password` (owner-only), and for TLS links `cert.pem`, `key.pem` (owner-only) and `ca.pem`.
A session finds its folder in `HRI_CREDENTIALS`, or else at `<keys dir>/<identity>` when that
exists (keys dir: `HRI_KEYS_DIR`, default `~/.local/state/hri/keys`). Secrets go into the Zenoh
configuration in memory only: never on a command line, never into a log.
"""

from __future__ import annotations

import ipaddress
import json
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import zenoh

from schemas.access import access_control, downsampling, qos_overwrites
from schemas.keys import validate_robot_id

DEFAULT_CONNECT = "tcp/127.0.0.1:7447"
DEFAULT_ROBOT = "op2"
CREDENTIALS_ENV = "HRI_CREDENTIALS"
KEYS_ENV = "HRI_KEYS_DIR"


class ConfigError(ValueError):
    """A configuration value is unusable; the message says which and how to fix it."""


def state_home(env: Mapping[str, str] = os.environ) -> Path:
    """`$XDG_STATE_HOME/hri`, XDG_STATE_HOME defaulting to `~/.local/state`."""
    xdg = env.get("XDG_STATE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".local/state") / "hri"


def default_state_dir(robot: str, env: Mapping[str, str] = os.environ) -> Path:
    """Where a service keeps what must survive a restart: `HRI_STATE_DIR`, else `<state home>/<robot>`
    (the reasoner's latched danger and episodes, the voice service's enrolled head)."""
    if env.get("HRI_STATE_DIR"):
        return Path(env["HRI_STATE_DIR"]).expanduser()
    return state_home(env) / robot


def default_keys_dir(env: Mapping[str, str] = os.environ) -> Path:
    if env.get(KEYS_ENV):
        return Path(env[KEYS_ENV]).expanduser()
    return state_home(env) / "keys"


def check_private(path: Path) -> None:
    """A secret must be a file only its owner can read (like ssh's private keys)."""
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise ConfigError(f"{path} is missing; run `hri keys init` to create the identities") from None
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise ConfigError(f"{path} can be read by others (mode {stat.S_IMODE(mode):04o}); chmod 600 it")


@dataclass(frozen=True)
class Credentials:
    """One identity's secrets on disk (the folder `hri keys init` writes)."""

    folder: Path
    user: str

    @classmethod
    def load(cls, folder: Path) -> Credentials:
        folder = Path(folder).expanduser()
        user_file = folder / "user"
        if not user_file.is_file():
            raise ConfigError(f"{folder} holds no identity (no 'user' file); run `hri keys init`")
        check_private(folder / "password")
        return cls(folder=folder, user=user_file.read_text().strip())

    @property
    def password_file(self) -> Path:
        return self.folder / "password"

    @property
    def cert(self) -> Path:
        return self.folder / "cert.pem"

    @property
    def key(self) -> Path:
        return self.folder / "key.pem"

    @property
    def ca(self) -> Path:
        return self.folder / "ca.pem"

    @property
    def has_tls(self) -> bool:
        return self.cert.is_file() and self.key.is_file() and self.ca.is_file()

    def settings(self, *, tls_connect: bool) -> dict[str, object]:
        """Client config entries (path -> value) for this identity: user/password, and the
        certificate for TLS links. Holds the password: keep it in memory or in an owner-only file."""
        out: dict[str, object] = {
            "transport/auth/usrpwd/user": self.user,
            "transport/auth/usrpwd/password": self.password_file.read_text().strip(),
        }
        if tls_connect:
            if not self.has_tls:
                raise ConfigError(f"a tls/ endpoint needs cert.pem, key.pem and ca.pem in {self.folder}; "
                                  "run `hri keys init`")
            check_private(self.key)
            out.update({"transport/link/tls/root_ca_certificate": str(self.ca),
                        "transport/link/tls/enable_mtls": True,
                        "transport/link/tls/connect_certificate": str(self.cert),
                        "transport/link/tls/connect_private_key": str(self.key)})
        return out


def find_credentials(identity: str | None,
                     env: dict[str, str] | os._Environ[str] = os.environ) -> Credentials | None:
    """`HRI_CREDENTIALS` if set, else `<keys dir>/<identity>` if it exists, else None (no auth)."""
    if env.get(CREDENTIALS_ENV):
        return Credentials.load(Path(env[CREDENTIALS_ENV]))
    if identity:
        folder = default_keys_dir(env) / identity
        if (folder / "user").is_file():
            return Credentials.load(folder)
    return None


@dataclass(frozen=True)
class BusSettings:
    """Where a service joins the bus: a zenoh config file, or client endpoints (and who it is)."""

    robot: str = DEFAULT_ROBOT
    config_file: Path | None = None
    connect: tuple[str, ...] = (DEFAULT_CONNECT,)
    credentials: Credentials | None = None
    identity: str | None = None

    @classmethod
    def from_env(cls, *, robot: str | None = None, connect: str | None = None,
                 identity: str | None = None) -> BusSettings:
        """`ZENOH_CONFIG` wins over `HRI_ZENOH_CONNECT`; explicit arguments win over both.
        `identity` names the default credentials folder (`<keys dir>/<identity>`)."""
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
        credentials = find_credentials(identity)
        return cls(robot=robot, config_file=config_file, connect=endpoints, credentials=credentials,
                   identity=identity)

    def refreshed(self) -> BusSettings:
        """Look for the default credentials again (`hri up` may have just made them)."""
        if self.credentials is not None or self.identity is None:
            return self
        found = find_credentials(self.identity)
        return self if found is None else replace(self, credentials=found)

    def zenoh_config(self) -> zenoh.Config:
        if self.config_file is not None:
            return zenoh.Config.from_file(str(self.config_file))
        return client_config(self.connect, self.credentials)

    @property
    def who(self) -> str:
        """Who this session claims to be, for logs: a user name, never a secret."""
        return self.credentials.user if self.credentials else "anonymous"


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


def client_settings(endpoints: tuple[str, ...] | list[str],
                    credentials: Credentials | None = None) -> dict[str, object]:
    """Client mode on explicit endpoints, multicast scouting off (sandboxes and containers block it),
    as config entries (path -> value)."""
    out: dict[str, object] = {"mode": "client", "connect/endpoints": list(endpoints),
                              "scouting/multicast/enabled": False}
    if credentials is not None:
        out.update(credentials.settings(tls_connect=any(e.startswith("tls/") for e in endpoints)))
    return out


def client_config(endpoints: tuple[str, ...] | list[str],
                  credentials: Credentials | None = None) -> zenoh.Config:
    """`client_settings` as a Zenoh configuration."""
    conf = zenoh.Config()
    for key, value in client_settings(endpoints, credentials).items():
        conf.insert_json5(key, json.dumps(value))
    return conf


# ---------------------------------------------------------------------------------------- router
@dataclass(frozen=True)
class RouterSecurity:
    """What a secured router needs: the deployment's keys folder (`hri keys init`), the robot whose
    keys the access rules cover, and whether the operator may write (`hri send`, the demo)."""

    keys_dir: Path
    robot: str = DEFAULT_ROBOT
    operator_writes: bool = True

    @property
    def folder(self) -> Path:
        return self.keys_dir / "router"

    def check(self) -> None:
        dictionary = self.folder / "dictionary"
        if not dictionary.is_file():
            raise ConfigError(f"no router credentials in {self.folder}; "
                              f"run `hri keys init --keys-dir {self.keys_dir}`")
        check_private(dictionary)


def is_loopback(endpoint: str) -> bool:
    """Whether a `proto/host:port` endpoint only listens on this machine."""
    host = endpoint.split("/", 1)[1].rsplit(":", 1)[0].strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_listen(listen: list[str], security: RouterSecurity | None) -> None:
    """Secure routers accept plain TCP on loopback only; any other interface must be TLS.
    (An open router, `security=None`, is the explicit classroom mode: anything goes.)"""
    if security is None:
        return
    for e in listen:
        proto = e.split("/", 1)[0]
        if proto == "tls":
            continue
        if not is_loopback(e):
            raise ConfigError(f"listen endpoint {e} is not loopback: use tls/{e.split('/', 1)[1]} "
                              "(mutual TLS with the deployment's CA) or run open on purpose (--open)")


STUCK_LINK_CLOSE_S = 0.25
"""How long the router waits for room on a link to a client that does not read before it closes that link,
when a message that must not be dropped (a motion goal, a voice command: congestion control "block") is for that
client too. While it waits, it forwards nothing else from the publisher: with Zenoh's default, 5 s, one stuck
subscriber (an `hri spy` whose terminal is paused) held the robot's goals back for 5 s (measured; README,
"A client that stops reading")."""

ROUTER_TRANSPORT: dict[str, object] = {
    "transport/link/tx/queue/congestion_control/block/wait_before_close": round(STUCK_LINK_CLOSE_S * 1e6),  # in µs
}


def router_config(listen: list[str], security: RouterSecurity | None = None) -> zenoh.Config:
    """A zenoh-python router listening only where told (the defaults listen on all interfaces);
    with `security`, every client must authenticate, and the access rules, input rate limits and
    input priorities of `schemas.access` apply."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps("router"))
    conf.insert_json5("listen/endpoints", json.dumps(listen))
    conf.insert_json5("connect/endpoints", "[]")
    conf.insert_json5("scouting/multicast/enabled", "false")
    for key, value in ROUTER_TRANSPORT.items():
        conf.insert_json5(key, json.dumps(value))
    if security is None:
        return conf
    check_listen(listen, security)
    security.check()
    for key, value in router_security_settings(security, listen).items():
        conf.insert_json5(key, json.dumps(value))
    return conf


def router_security_settings(security: RouterSecurity, listen: list[str], *,
                             folder: str | None = None) -> dict[str, object]:
    """Config entries (path -> value) that secure a router; `folder` is where the router's files
    are seen from (a container's mount point), by default where they are here."""
    base = folder or str(security.folder)
    tls = any(e.startswith("tls/") for e in listen)
    out: dict[str, object] = {
        "transport/auth/usrpwd/dictionary_file": f"{base}/dictionary",
        "access_control": access_control(security.robot, tls=True, operator_writes=security.operator_writes),
        "downsampling": downsampling(security.robot),
        "qos/network": qos_overwrites(security.robot),
    }
    if tls:
        if folder is None:
            for name in ("cert.pem", "key.pem", "ca.pem"):
                if not (security.folder / name).is_file():
                    raise ConfigError(f"tls/ listening needs {security.folder / name}; run `hri keys init`")
            check_private(security.folder / "key.pem")
        out.update({"transport/link/tls/listen_certificate": f"{base}/cert.pem",
                    "transport/link/tls/listen_private_key": f"{base}/key.pem",
                    "transport/link/tls/root_ca_certificate": f"{base}/ca.pem",
                    "transport/link/tls/enable_mtls": True})
    return out


def nest(flat: dict[str, object]) -> dict[str, object]:
    """`{"a/b": 1}` -> `{"a": {"b": 1}}`: config entries as a Zenoh JSON5 configuration file."""
    out: dict[str, object] = {}
    for path, value in flat.items():
        node = out
        *parents, leaf = path.split("/")
        for part in parents:
            node = node.setdefault(part, {})  # type: ignore[assignment]
        node[leaf] = value
    return out
