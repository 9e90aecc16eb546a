"""`hri`: run the whole robot (`up`, `demo`) and look at it (`status`, `spy`, `send`)."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from schemas.access import OPERATOR
from schemas.keys import SERVICES
from schemas.messages import Command, Mark, MarkObservation, SceneCommand, Shape, VoiceCommand
from services.cli import keys as deployment_keys
from services.cli import probe
from services.cli.launcher import Launcher, run_until_signalled
from services.cli.router import DEFAULT_PORT
from services.cli.utterance import DEFAULT_VOICE
from services.runtime import default_keys_dir
from services.runtime.cli import ConnectOption, RobotOption

app = typer.Typer(add_completion=False, no_args_is_help=True, help=__doc__)
send_app = typer.Typer(add_completion=False, no_args_is_help=True,
                       help="Publish one valid message as a service would, for testing by hand.")
app.add_typer(send_app, name="send")
app.add_typer(deployment_keys.app, name="keys")
console = Console()
if not console.is_terminal and "COLUMNS" not in os.environ:
    console = Console(width=120)  # piped or logged (CI): rich would wrap the tables at 80 columns


@app.command()
def up(
    port: Annotated[int, typer.Option(help="Port of the embedded router on 127.0.0.1")] = DEFAULT_PORT,
    connect: Annotated[str | None, typer.Option(
        help="Join an existing router at this endpoint instead of starting one")] = None,
    robot: RobotOption = None,
    only: Annotated[list[str] | None, typer.Option(
        "--only", help=f"Start only these services (repeatable): {', '.join(SERVICES)}")] = None,
    no_restart: Annotated[bool, typer.Option("--no-restart", help="Do not restart crashed services")] = False,
    keys_dir: Annotated[Path | None, typer.Option("--keys-dir", envvar="HRI_KEYS_DIR", help=(
        "The deployment's identities (made here by `hri keys init` on first use) "
        "[default: ~/.local/state/hri/keys]"))] = None,
    listen: Annotated[list[str] | None, typer.Option("--listen", help=(
        "Also listen here (repeatable); other machines must use TLS, e.g. tls/0.0.0.0:7448"))] = None,
    no_operator_writes: Annotated[bool, typer.Option("--no-operator-writes", help=(
        "Withhold the operator's puts (hri send, the demo)"))] = False,
    open_bus: Annotated[bool, typer.Option("--open", help=(
        "No authentication, no access rules: anyone who reaches the router can move the robot "
        "(a classroom on a closed network)"))] = False,
) -> None:
    """Start the embedded Zenoh router and the five services; Ctrl-C stops them all.

    Secure by default: every service runs as its own identity, the router listens on loopback,
    requires credentials and applies the access rules generated from schemas/access.py.
    """
    folder = None if open_bus else (keys_dir or default_keys_dir())
    try:
        if folder is not None and not deployment_keys.exists(folder) and connect is not None:
            folder = None  # joining a router: anonymous unless this deployment's keys were copied here
        launcher = Launcher(only or SERVICES, port=port, connect=connect, robot=robot, restart=not no_restart,
                            keys_dir=folder, operator_writes=not no_operator_writes, listen=listen or [])
        if folder is not None and not deployment_keys.exists(folder):  # made where the router runs
            deployment_keys.init(folder)
            typer.echo(f"created this deployment's identities in {folder}", err=True)
        raise typer.Exit(run_until_signalled(launcher))
    except ValueError as exc:  # unknown service, or a ConfigError (listen endpoint, keys)
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None


@app.command()
def status(
    robot: RobotOption = None,
    connect: ConnectOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table")] = False,
    timeout: Annotated[float, typer.Option(help="Seconds to wait for answers")] = 2.0,
) -> None:
    """Which services are alive, and their health. Exits 1 unless all five are alive."""
    with probe.client_session(robot, connect) as (session, keys):
        rows = probe.gather_status(session, keys, timeout)
    if as_json:
        out = {n: {"alive": r.get("alive", False),
                   "health": r["health"].model_dump(mode="json") if r.get("health") else None}
               for n, r in rows.items()}
        typer.echo(json.dumps(out, indent=2))
    else:
        console.print(probe.status_table(rows, keys.robot))
    raise typer.Exit(0 if all(rows[s].get("alive") for s in SERVICES) else 1)


@app.command()
def spy(
    keyexpr: Annotated[str | None, typer.Argument(help="Key expression [default: hri/<robot>/**]")] = None,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Live, readable view of the traffic (and services coming and going) until Ctrl-C."""
    stop = threading.Event()
    with probe.client_session(robot, connect) as (session, keys):
        try:
            probe.spy(session, keyexpr or keys.all, keys.prefix, console, stop)
        except KeyboardInterrupt:
            stop.set()


@app.command()
def demo(
    scenario: Annotated[str, typer.Option(
        help="A built-in scenario name or a YAML scenario file (see services/cli/scenarios/)")] = "paper",
    out: Annotated[Path, typer.Option(help="Folder for the spoken WAVs, the timeline and the service logs "
                                           "(emptied first)")] = Path("hri-demo"),
    port: Annotated[int, typer.Option(help="Router port on 127.0.0.1 (0: a free one)")] = 0,
    voice: Annotated[str, typer.Option(help="espeak-ng voice that speaks the commands")] = DEFAULT_VOICE,
    list_scenarios: Annotated[bool, typer.Option("--list", help="List the built-in scenarios and exit")] = False,
) -> None:
    """Run a scenario (default: the paper's experiment) on the simulated robot, with a live timeline.

    Exits 0 when every step turned out as the scenario expects.
    """
    from services.cli import scenario as scenarios
    from services.cli.demo import run_demo

    if list_scenarios:
        for name in scenarios.builtin_names():
            typer.echo(f"{name:<24} {scenarios.load(name).description.strip().splitlines()[0][:80]}")
        raise typer.Exit(0)
    try:
        loaded = scenarios.load(scenario)
    except scenarios.ScenarioError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    raise typer.Exit(run_demo(loaded, out, port=port, voice=voice, console=console))


@send_app.command("command")
def send_command(
    command: Annotated[str, typer.Argument(help="stand, down, yes, no, go, stop, or 'none' for unmatched speech")],
    confidence: Annotated[float, typer.Option(min=0.0, max=1.0)] = 0.95,
    text: Annotated[str | None, typer.Option(help="The heard text [default: the command]")] = None,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Publish a VoiceCommand as the voice service would."""
    cmd = None if command.lower() == "none" else _choice(Command, command.lower(), "command")
    msg = VoiceCommand(command=cmd, text=text if text is not None else command, confidence=confidence,
                       engine="hri-send")
    with probe.client_session(robot, connect, OPERATOR) as (session, keys):
        sent = probe.publish_once(session, keys.voice_command, msg)
    typer.echo(sent.model_dump_json())


@send_app.command("mark")
def send_mark(
    shape: Annotated[str, typer.Argument(help="X, O, TRIANGLE, or 'none' for a frame with no mark")],
    confidence: Annotated[float, typer.Option(min=0.0, max=1.0)] = 0.99,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Publish a MarkObservation as the vision service would."""
    marks = [] if shape.lower() == "none" else [
        Mark(shape=_choice(Shape, shape.upper(), "shape"), confidence=confidence, box=(200, 120, 240, 240))]
    with probe.client_session(robot, connect, OPERATOR) as (session, keys):
        sent = probe.publish_once(session, keys.vision_marks, MarkObservation(marks=marks, frame=0))
    typer.echo(sent.model_dump_json())


@send_app.command("scene")
def send_scene(
    shape: Annotated[str, typer.Argument(help="X, O, TRIANGLE, or 'none': what the synthetic camera shows")],
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Tell a vision service on a synthetic source what card to hold up (frames go through the detector)."""
    value = None if shape.lower() == "none" else _choice(Shape, shape.upper(), "shape")
    with probe.client_session(robot, connect, OPERATOR) as (session, keys):
        sent = probe.publish_once(session, keys.vision_scene, SceneCommand(shape=value))
    typer.echo(sent.model_dump_json())


def _choice(enum: type, value: str, what: str):  # type: ignore[no-untyped-def]
    try:
        return enum(value)
    except ValueError:
        raise typer.BadParameter(f"unknown {what} {value!r}; choose from {', '.join(e.value for e in enum)}") from None


if __name__ == "__main__":
    app()
