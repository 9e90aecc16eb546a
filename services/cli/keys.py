"""`hri keys`: the identities of one deployment (DESIGN.md, safety invariant 6).

`hri keys init` writes, under the keys folder (`HRI_KEYS_DIR`, default `~/.local/state/hri/keys`):

    ca/ca.pem, ca/ca.key              a small certificate authority (only `init`/`rotate` use the key)
    router/dictionary                 user:password lines the router checks (owner-only)
    router/cert.pem, key.pem, ca.pem  the router's TLS certificate (names: localhost, router, zenoh, --host)
    <identity>/user, password         one per service, `observer` and `operator` (password owner-only)
    <identity>/cert.pem, key.pem, ca.pem   its client certificate (common name = identity) for TLS links

A machine that runs a service needs only that service's folder (copy it, keep it 0600); the
router needs `router/`. Keys and passwords come from `secrets` and `cryptography`; nothing is
printed or logged but names and paths.
"""

from __future__ import annotations

import datetime
import ipaddress
import json
import os
import secrets
import shutil
from collections.abc import Iterable
from pathlib import Path
from typing import Annotated

import typer
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from schemas.access import ACCESS, IDENTITIES, Kind
from schemas.keys import SERVICES
from services.runtime.config import (
    DEFAULT_CONNECT,
    ROUTER_TRANSPORT,
    ConfigError,
    Credentials,
    RouterSecurity,
    client_settings,
    default_keys_dir,
    nest,
    parse_endpoints,
    router_security_settings,
)

ROUTER_NAMES = ("localhost", "127.0.0.1", "::1", "router", "zenoh")
"""Names the router's certificate is valid for, plus `--host` ones (what clients connect to)."""
CA_DAYS = 3650
LEAF_DAYS = 825


# ---------------------------------------------------------------------------------------- files
def _write_private(path: Path, data: bytes) -> None:
    """Write a secret: created owner-only (never briefly world-readable), replaced atomically."""
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    tmp = path.with_name(path.name + ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def _write_public(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    path.write_bytes(data)


def _pem_key(key: ec.EllipticCurvePrivateKey) -> bytes:
    return key.private_bytes(
        serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
    )


def _pem(cert: x509.Certificate) -> bytes:
    return cert.public_bytes(serialization.Encoding.PEM)


# ---------------------------------------------------------------------------------------- CA
class Authority:
    """The deployment's CA: issues one certificate per identity and one for the router."""

    def __init__(self, cert: x509.Certificate, key: ec.EllipticCurvePrivateKey) -> None:
        self.cert = cert
        self.key = key

    @classmethod
    def create(cls, folder: Path) -> Authority:
        key = ec.generate_private_key(ec.SECP256R1())
        name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "hri deployment CA")])
        now = datetime.datetime.now(datetime.UTC)
        cert = (
            x509.CertificateBuilder()
            .subject_name(name)
            .issuer_name(name)
            .public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=CA_DAYS))
            .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
            .add_extension(
                x509.KeyUsage(
                    digital_signature=True,
                    key_cert_sign=True,
                    crl_sign=True,
                    content_commitment=False,
                    key_encipherment=False,
                    data_encipherment=False,
                    key_agreement=False,
                    encipher_only=False,
                    decipher_only=False,
                ),
                critical=True,
            )
            .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
            .sign(key, hashes.SHA256())
        )
        _write_private(folder / "ca.key", _pem_key(key))
        _write_public(folder / "ca.pem", _pem(cert))
        return cls(cert, key)

    @classmethod
    def load(cls, folder: Path) -> Authority:
        try:
            cert = x509.load_pem_x509_certificate((folder / "ca.pem").read_bytes())
            key = serialization.load_pem_private_key((folder / "ca.key").read_bytes(), password=None)
        except FileNotFoundError as exc:
            raise ConfigError(f"no CA in {folder}: run `hri keys init` first") from exc
        assert isinstance(key, ec.EllipticCurvePrivateKey)
        return cls(cert, key)

    def issue(self, folder: Path, common_name: str, *, server_names: Iterable[str] = ()) -> None:
        """Write `cert.pem`, `key.pem` (owner-only) and `ca.pem` for `common_name` into `folder`."""
        key = ec.generate_private_key(ec.SECP256R1())
        now = datetime.datetime.now(datetime.UTC)
        names = list(dict.fromkeys(server_names))
        usages = [ExtendedKeyUsageOID.CLIENT_AUTH] + ([ExtendedKeyUsageOID.SERVER_AUTH] if names else [])
        builder = (
            x509.CertificateBuilder()
            .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, common_name)]))
            .issuer_name(self.cert.subject)
            .public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=LEAF_DAYS))
            .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
            .add_extension(x509.ExtendedKeyUsage(usages), critical=False)
            .add_extension(
                x509.AuthorityKeyIdentifier.from_issuer_public_key(self.key.public_key()), critical=False
            )
        )
        if names:
            builder = builder.add_extension(
                x509.SubjectAlternativeName([_san(n) for n in names]), critical=False
            )
        cert = builder.sign(self.key, hashes.SHA256())
        _write_private(folder / "key.pem", _pem_key(key))
        _write_public(folder / "cert.pem", _pem(cert))
        _write_public(folder / "ca.pem", _pem(self.cert))


def _san(name: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(name))
    except ValueError:
        return x509.DNSName(name)


# ---------------------------------------------------------------------------------------- identities
def _new_password(folder: Path, identity: str) -> None:
    _write_public(folder / "user", f"{identity}\n".encode())
    _write_private(folder / "password", (secrets.token_urlsafe(24) + "\n").encode())


def _write_dictionary(keys_dir: Path, identities: Iterable[str]) -> None:
    """The router's `user:password` dictionary, rebuilt from the identity folders."""
    lines = []
    for identity in identities:
        folder = keys_dir / identity
        if (folder / "password").is_file():
            lines.append(f"{identity}:{(folder / 'password').read_text().strip()}")
    _write_private(keys_dir / "router" / "dictionary", ("\n".join(lines) + "\n").encode())


def exists(keys_dir: Path) -> bool:
    return (keys_dir / "router" / "dictionary").is_file()


def init(
    keys_dir: Path, *, hosts: Iterable[str] = (), identities: Iterable[str] = IDENTITIES, force: bool = False
) -> list[str]:
    """Create the CA, the router's credentials and one identity per name. Returns the identities.

    Refuses to overwrite an existing deployment unless `force` (that would lock out every
    machine that holds the old secrets)."""
    keys_dir = Path(keys_dir).expanduser()
    if exists(keys_dir) and not force:
        raise ConfigError(
            f"{keys_dir} already holds identities; use `hri keys rotate` or --force to replace all"
        )
    if keys_dir.exists() and any(keys_dir.iterdir()) and not force:
        raise ConfigError(f"{keys_dir} is not empty; choose another folder or pass --force")
    # Built aside and renamed into place: a reader never sees half a deployment.
    keys_dir.parent.mkdir(parents=True, exist_ok=True)
    staging = keys_dir.with_name(f".{keys_dir.name}.{os.getpid()}.new")
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir(mode=0o700)
    ca = Authority.create(staging / "ca")
    names = list(identities)
    for identity in names:
        _new_password(staging / identity, identity)
        ca.issue(staging / identity, identity)
    ca.issue(staging / "router", "router", server_names=[*ROUTER_NAMES, *hosts])
    _write_dictionary(staging, names)
    if keys_dir.exists():
        shutil.rmtree(keys_dir)
    os.replace(staging, keys_dir)
    return names


def hand_to_containers(keys_dir: Path, uid: int, gid: int | None = None) -> None:
    """Give the router's and the five services' folders to the user the containers run as (the
    image's `hri`, uid 10001), so that files only their owner may read are readable in there. The
    CA and the observer's and operator's folders stay with the person who made them."""
    keys_dir = Path(keys_dir).expanduser()
    for name in ("router", *SERVICES):
        folder = keys_dir / name
        for path in (folder, *folder.iterdir()):
            try:
                os.chown(path, uid, uid if gid is None else gid)
            except PermissionError:
                raise ConfigError(
                    f"cannot give {path} to uid {uid}: run as root (sudo hri keys ...)"
                ) from None


def rotate(keys_dir: Path, identity: str) -> None:
    """New password and certificate for one identity (the router must be restarted to see it)."""
    keys_dir = Path(keys_dir).expanduser()
    if identity == "router":
        raise ConfigError("rotate the router's certificate with `hri keys init --force` or `reissue-router`")
    if identity not in IDENTITIES:
        raise ConfigError(f"unknown identity {identity!r}; choose from {', '.join(IDENTITIES)}")
    ca = Authority.load(keys_dir / "ca")
    _new_password(keys_dir / identity, identity)
    ca.issue(keys_dir / identity, identity)
    _write_dictionary(keys_dir, IDENTITIES)


def reissue_router(keys_dir: Path, hosts: Iterable[str]) -> None:
    """A new router certificate valid for the usual names plus `hosts` (a new address to reach it)."""
    keys_dir = Path(keys_dir).expanduser()
    Authority.load(keys_dir / "ca").issue(keys_dir / "router", "router", server_names=[*ROUTER_NAMES, *hosts])


def router_config_file(security: RouterSecurity, listen: list[str], folder: str) -> str:
    """A complete Zenoh JSON5 configuration for a router (zenohd or ours) that sees the router's
    files at `folder`: the same authentication and generated access rules as `hri up`."""
    flat: dict[str, object] = {
        "mode": "router",
        "listen/endpoints": listen,
        "scouting/multicast/enabled": False,
        **ROUTER_TRANSPORT,
        **router_security_settings(security, listen, folder=folder),
    }
    return json.dumps(nest(flat), indent=2) + "\n"


def client_config_file(keys_dir: Path, identity: str, connect: str) -> Path:
    """Write `<keys>/<identity>/zenoh.json5` (owner-only: it holds the password): a Zenoh client
    configuration as this identity, for zenoh-cli (`zenoh --config ...`) or `ZENOH_CONFIG`."""
    credentials = Credentials.load(Path(keys_dir).expanduser() / identity)
    path = credentials.folder / "zenoh.json5"
    text = json.dumps(nest(client_settings(parse_endpoints(connect), credentials)), indent=2) + "\n"
    _write_private(path, text.encode())
    return path


# ---------------------------------------------------------------------------------------- CLI
app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Identities of this deployment: passwords, a small CA and certificates.",
)
KeysDir = Annotated[
    Path | None,
    typer.Option("--keys-dir", envvar="HRI_KEYS_DIR", help="Keys folder [default: ~/.local/state/hri/keys]"),
]


ContainerUid = Annotated[
    int | None,
    typer.Option(
        "--container-uid",
        help="For docker compose: give the router's and services' folders to this uid "
        "(the image's user is 10001; needs root)",
    ),
]


def _fail(exc: Exception) -> typer.Exit:
    typer.echo(f"error: {exc}", err=True)
    return typer.Exit(2)


@app.command("init")
def init_cmd(
    keys_dir: KeysDir = None,
    host: Annotated[
        list[str] | None,
        typer.Option("--host", help="Another name or address clients use to reach the router (repeatable)"),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace every existing secret")] = False,
    container_uid: ContainerUid = None,
) -> None:
    """Create the deployment's identities (five services, observer, operator) and the router's."""
    folder = keys_dir or default_keys_dir()
    try:
        names = init(folder, hosts=host or [], force=force)
        if container_uid is not None:
            hand_to_containers(folder, container_uid)
    except ConfigError as exc:
        raise _fail(exc) from None
    typer.echo(f"created {len(names)} identities ({', '.join(names)}) and the router's in {folder}")


@app.command("rotate")
def rotate_cmd(
    identity: Annotated[str, typer.Argument(help=f"One of {', '.join(IDENTITIES)}")],
    keys_dir: KeysDir = None,
    container_uid: ContainerUid = None,
) -> None:
    """Give one identity a new password and certificate; restart the router and that service."""
    folder = keys_dir or default_keys_dir()
    try:
        rotate(folder, identity)
        if container_uid is not None:
            hand_to_containers(folder, container_uid)
    except ConfigError as exc:
        raise _fail(exc) from None
    typer.echo(
        f"rotated {identity} in {folder}; restart the router, then copy {folder / identity} "
        "to the machine that runs it"
    )


@app.command("reissue-router")
def reissue_router_cmd(
    host: Annotated[list[str], typer.Option("--host", help="Extra router name (repeatable)")],
    keys_dir: KeysDir = None,
) -> None:
    """A new router certificate that is also valid for the given names or addresses."""
    folder = keys_dir or default_keys_dir()
    try:
        reissue_router(folder, host)
    except ConfigError as exc:
        raise _fail(exc) from None
    typer.echo(f"router certificate reissued for {', '.join([*ROUTER_NAMES, *host])}")


@app.command("show")
def show_cmd(keys_dir: KeysDir = None) -> None:
    """The identities on disk and what each may put (from the access table); no secrets."""
    folder = keys_dir or default_keys_dir()
    for identity in IDENTITIES:
        present = (folder / identity / "password").is_file()
        puts = [row.key for row in ACCESS if row.kind is Kind.TOPIC and identity in row.owners]
        typer.echo(f"{identity:<9} {'ok     ' if present else 'missing'} puts: {', '.join(puts) or '-'}")


@app.command("client-config")
def client_config_cmd(
    identity: Annotated[str, typer.Argument(help="observer for zenoh-cli; a service for ZENOH_CONFIG")],
    connect: Annotated[str, typer.Option(help="Router endpoint(s), comma-separated")] = DEFAULT_CONNECT,
    keys_dir: KeysDir = None,
) -> None:
    """Write a Zenoh client configuration as IDENTITY (owner-only) and print its path."""
    try:
        path = client_config_file(keys_dir or default_keys_dir(), identity, connect)
    except ConfigError as exc:
        raise _fail(exc) from None
    typer.echo(str(path))


@app.command("router-config")
def router_config_cmd(
    robot: Annotated[str, typer.Option(envvar="HRI_ROBOT", help="Robot id the rules cover")] = "op2",
    listen: Annotated[list[str] | None, typer.Option("--listen", help="Listen endpoint (repeatable)")] = None,
    folder: Annotated[str, typer.Option(help="Where the router sees its files (a container mount)")] = "",
    no_operator_writes: Annotated[
        bool, typer.Option("--no-operator-writes", help="Withhold the operator's puts")
    ] = False,
    out: Annotated[Path | None, typer.Option(help="Write here instead of printing")] = None,
    keys_dir: KeysDir = None,
) -> None:
    """Print a Zenoh JSON5 router configuration (zenohd or `services.cli.router --config`)."""
    kd = keys_dir or default_keys_dir()
    security = RouterSecurity(kd, robot=robot, operator_writes=not no_operator_writes)
    text = router_config_file(security, listen or ["tls/0.0.0.0:7447"], folder or str(security.folder))
    if out is None:
        typer.echo(text, nl=False)
    else:
        out.write_text(text)
        typer.echo(f"wrote {out}")
