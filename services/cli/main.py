"""`hri`: run the whole robot (`up`, `demo`), look at it (`status`, `spy`, `send`, `view`), record and replay it."""

from __future__ import annotations

import json
import os
import textwrap
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Annotated, NoReturn

import typer
import zenoh
from rich.console import Console

from schemas.access import OBSERVER, OPERATOR
from schemas.keys import SERVICES, Keys
from schemas.messages import (
    Command,
    Decision,
    Health,
    HealthStatus,
    Mark,
    MarkObservation,
    SceneCommand,
    Shape,
    VoiceCommand,
)
from services.cli import keys as deployment_keys
from services.cli import probe
from services.cli.launcher import Launcher, run_until_signalled
from services.cli.router import DEFAULT_PORT
from services.cli.utterance import DEFAULT_VOICE
from services.runtime import ConfigError, ServiceContext, SessionRefused, configure_logging, default_keys_dir
from services.runtime.cli import ConnectOption, RobotOption
from services.runtime.logs import settings_error as log_settings_error
from services.runtime.signals import stop_on_signals

# rich_markup_mode=None: help text is printed as written ("[default: op2]" is not read as Rich markup)
app = typer.Typer(add_completion=False, no_args_is_help=True, help=__doc__, rich_markup_mode=None)
send_app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                       help="Publish one valid message as a service would, for testing by hand.")
app.add_typer(send_app, name="send")
app.add_typer(deployment_keys.app, name="keys")
console = Console()
if not console.is_terminal and "COLUMNS" not in os.environ:
    console = Console(width=120)  # piped or logged (CI): rich would wrap the tables at 80 columns

NO_ROUTER_HINT = ("start the robot with `hri up` (or `docker compose up`), or point at its router with "
                  "--connect tcp/HOST:PORT (or HRI_ZENOH_CONNECT)")


def fail(message: str, code: int = 1) -> NoReturn:
    """One line on stderr and a non-zero exit: what a person needs, without a traceback."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


@contextmanager
def bus(robot: str | None, connect: str | None,
        identity: str = OBSERVER) -> Iterator[tuple[zenoh.Session, Keys]]:
    """A session for status/spy/send as `identity`; no router, a refusal or bad settings end the
    command with one line."""
    configure_logging(os.environ.get("HRI_LOG_LEVEL") or "error")  # not the session's retry warnings
    with ExitStack() as stack:
        try:
            pair = stack.enter_context(probe.client_session(robot, connect, identity))
        except ConfigError as exc:
            fail(f"invalid configuration: {exc}", 2)
        except probe.BusUnreachable as exc:
            fail(f"{exc}: {NO_ROUTER_HINT}")
        except SessionRefused as exc:  # a router is there and refused these credentials (or none)
            fail(str(exc), 2)
        yield pair


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
    if problem := log_settings_error():  # every service would exit 2 with it, and be restarted
        fail(problem, 2)
    folder = None if open_bus else (keys_dir or default_keys_dir())
    if folder is not None and not deployment_keys.exists(folder) and connect is not None:
        folder = None  # joining a router: anonymous unless this deployment's keys were copied here
    try:
        launcher = Launcher(only or SERVICES, port=port, connect=connect, robot=robot, restart=not no_restart,
                            keys_dir=folder, operator_writes=not no_operator_writes, listen=listen or [])
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None
    try:
        if folder is not None and not deployment_keys.exists(folder):  # made where the router runs
            deployment_keys.init(folder)
            typer.echo(f"created this deployment's identities in {folder}", err=True)
        code = run_until_signalled(launcher)
    except ConfigError as exc:  # a listen endpoint a secure router refuses, unreadable keys
        fail(str(exc), 2)
    except zenoh.ZError as exc:  # only the embedded router's listener can fail here
        why = "the port is in use" if "in use" in str(exc) else str(exc).splitlines()[0][:160]
        fail(f"cannot start the router on {launcher.endpoint}: {why}; choose another port with --port, "
             f"or join the router already there with --connect {launcher.endpoint}")
    raise typer.Exit(code)


@app.command()
def status(
    robot: RobotOption = None,
    connect: ConnectOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table")] = False,
    timeout: Annotated[float, typer.Option(help="Seconds to wait for answers")] = 2.0,
    service: Annotated[str | None, typer.Option(
        help=f"Only this service ({', '.join(SERVICES)}): exits 0 when it is alive and reports ok "
             "(the containers' health check)")] = None,
) -> None:
    """Which services are alive, and their health. Exits 1 unless all five are alive (1 also when no router
    answers, 2 for invalid settings)."""
    if service is not None and service not in SERVICES:
        raise typer.BadParameter(f"unknown service {service!r}; choose from {', '.join(SERVICES)}",
                                 param_hint="--service")
    with bus(robot, connect) as (session, keys):
        rows = probe.gather_status(session, keys, timeout, service)
    if as_json:
        out = {n: {"alive": r.get("alive", False),
                   "health": r["health"].model_dump(mode="json") if r.get("health") else None}
               for n, r in rows.items()}
        typer.echo(json.dumps(out, indent=2))
    else:
        console.print(probe.status_table(rows, keys.robot))
    if service is not None:
        health = rows[service].get("health")
        raise typer.Exit(0 if rows[service].get("alive") and isinstance(health, Health)
                         and health.status is HealthStatus.OK else 1)
    raise typer.Exit(0 if all(rows[s].get("alive") for s in SERVICES) else 1)


@app.command()
def spy(
    keyexpr: Annotated[str | None, typer.Argument(help="Key expression [default: hri/<robot>/**]")] = None,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Live, readable view of the traffic (and services coming and going) until Ctrl-C or SIGTERM."""
    stop = stop_on_signals()
    with bus(robot, connect) as (session, keys):
        probe.spy(session, keyexpr or keys.all, keys.prefix, console, stop)


OUT_HELP = ("Folder for the spoken WAVs, the timeline, the service logs and the robot's own state; a run "
            "replaces only what an earlier run left there, and refuses a non-empty folder it did not make")


@app.command()
def demo(
    scenario: Annotated[str, typer.Option(
        help="A built-in scenario name or a YAML scenario file (see services/cli/scenarios/)")] = "paper",
    out: Annotated[Path, typer.Option(help=OUT_HELP)] = Path("hri-demo"),
    port: Annotated[int, typer.Option(help="Router port on 127.0.0.1 (0: a free one)")] = 0,
    voice: Annotated[str, typer.Option(help="espeak-ng voice that speaks the commands")] = DEFAULT_VOICE,
    list_scenarios: Annotated[bool, typer.Option("--list", help="List the built-in scenarios and exit")] = False,
    record_to: Annotated[Path | None, typer.Option("--record", help="Also record everything on the bus into "
                                                   "this MCAP file (see `hri record`)")] = None,
) -> None:
    """Run a scenario (default: the paper's experiment) on the simulated robot, with a live timeline.

    Exits 0 when every step turned out as the scenario expects.
    """
    from services.cli import scenario as scenarios
    from services.cli.demo import OutputFolderError, run_demo

    if list_scenarios:
        for name in scenarios.builtin_names():  # whole descriptions, wrapped at word boundaries
            typer.echo(textwrap.fill(" ".join(scenarios.load(name).description.split()) or "-", width=100,
                                     initial_indent=f"{name:<12} ", subsequent_indent=" " * 13))
        raise typer.Exit(0)
    try:
        loaded = scenarios.load(scenario)
    except scenarios.ScenarioError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    folder = record_to.resolve().parent if record_to is not None else None
    if folder is not None and not folder.is_dir() and folder != out.resolve():  # `out` is made afresh
        typer.echo(f"error: no folder {record_to.parent} for {record_to.name}", err=True)
        raise typer.Exit(2)
    try:
        code = run_demo(loaded, out, port=port, voice=voice, console=console, record=record_to)
    except OutputFolderError as exc:
        fail(str(exc), 2)
    raise typer.Exit(code)


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
    with bus(robot, connect, OPERATOR) as (session, keys):
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
    with bus(robot, connect, OPERATOR) as (session, keys):
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
    with bus(robot, connect, OPERATOR) as (session, keys):
        sent = probe.publish_once(session, keys.vision_scene, SceneCommand(shape=value))
    typer.echo(sent.model_dump_json())


@app.command()
def why(
    robot: RobotOption = None,
    connect: ConnectOption = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print the structured Explanation as JSON")] = False,
    timeout: Annotated[float, typer.Option(help="Seconds to wait for the reasoner's answer")] = 5.0,
) -> None:
    """Ask the robot why it did what it did last, as if asked aloud (it also says the answer).

    The reasoner answers from its episodic memory on hri/<robot>/reasoner/explain. Exits 1 when
    no reasoner answers.
    """
    from schemas.messages import Explanation

    with probe.client_session(robot, connect) as (session, keys):
        replies = list(session.get(keys.reasoner_explain, timeout=timeout))
    answers = [Explanation.model_validate_json(r.ok.payload.to_bytes()) for r in replies if r.ok is not None]
    errors = [r.err.payload.to_string() for r in replies if r.err is not None]
    if not answers:
        missing = f"no reasoner answered on {keys.reasoner_explain} within {timeout:g} s"
        typer.echo(errors[0] if errors else missing, err=True)
        raise typer.Exit(1)
    explanation = answers[0]
    if as_json:
        typer.echo(explanation.model_dump_json(indent=2))
        return
    typer.echo(explanation.text)
    for e in explanation.evidence:
        ago = f"{e.ago_s:.0f} s ago" if e.ago_s is not None else "earlier"
        typer.echo(f"  {'heard' if e.kind == 'command' else 'saw'} {e.what}, {ago} (episode {e.episode})")


@app.command()
def record(
    file: Annotated[Path, typer.Argument(help="The MCAP file to write")],
    duration: Annotated[float | None, typer.Option(min=0.1, help="Stop after this many seconds "
                                                   "[default: at Ctrl-C]")] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Replace FILE if it exists")] = False,
    images: Annotated[bool, typer.Option("--images/--no-images", help="Record the camera preview (about 1.7 MB "
                                         "a minute) [default: yes]")] = True,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Record every message of the robot (hri/<robot>/**) into an MCAP file, until Ctrl-C or --duration."""
    from services.cli.record import record as record_to
    from services.runtime import run_service

    if file.exists() and not overwrite:
        typer.echo(f"error: {file} exists (use --overwrite to replace it)", err=True)
        raise typer.Exit(2)
    if not file.parent.is_dir():
        typer.echo(f"error: no folder {file.parent} for {file.name}", err=True)
        raise typer.Exit(2)
    done = []
    code = run_service("record", lambda ctx: done.append(record_to(ctx, file, duration, images=images)),
                       robot=robot, connect=connect, identity=OBSERVER)
    if done:
        console.print(done[0].table())
    raise typer.Exit(code)


@app.command()
def replay(
    file: Annotated[Path, typer.Argument(help="An MCAP recording made by `hri record` or `hri demo --record`")],
    rate: Annotated[float, typer.Option(min=0.0, help="Speed: 2 plays twice as fast, 0 as fast as possible")] = 1.0,
    all_keys: Annotated[bool, typer.Option("--all", help="Replay every recorded key, not only the inputs "
                                                         "(marks, commands)")] = False,
    check: Annotated[bool, typer.Option("--check", help="Compare the decisions made now with the recorded "
                                                        "ones; exit 1 when they differ")] = False,
    settle: Annotated[float, typer.Option(help="With --check: seconds without a new decision that end "
                                               "the replay")] = 3.0,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """Publish a recording's inputs (marks seen, commands heard) again, with their original timing."""
    from services.cli import replay as rp
    from services.cli.mcapfile import RecordingError, read_recording
    from services.runtime import run_service

    try:
        recorded = list(read_recording(file))
        chosen = rp.select(recorded, all_keys=all_keys)
        expected = rp.recorded_decisions(recorded)
    except RecordingError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    if not chosen:
        what = "messages" if all_keys else "marks or commands"
        typer.echo(f"error: {file} holds no {what} to replay", err=True)
        raise typer.Exit(2)
    made: list[list[Decision]] = []  # the decisions made during the replay, once it has run to its end

    def body(ctx: ServiceContext) -> None:
        watch = rp.DecisionWatch(ctx) if check else None
        result = rp.Replayer(ctx, chosen, rate=rate).run()
        for key in result.unmatched:
            console.print(f"[yellow]nobody was listening on {key} when the replay started", highlight=False)
        skipped = f" ({result.skipped} invalid, left out)" if result.skipped else ""
        console.print(f"replayed {result.published} message(s) in {result.seconds:.1f} s{skipped}", highlight=False)
        if watch is not None and not result.interrupted:
            made.append(watch.settle(len(expected), settle, timeout=settle + 30.0))

    code = run_service("replay", body, robot=robot, connect=connect, identity=OPERATOR)
    if check and code == 0:
        if not made:
            console.print("[yellow]interrupted: no check")
            raise typer.Exit(130)
        problems = rp.compare(expected, made[0])
        console.print(f"{len(expected)} decision(s) recorded, {len(made[0])} made now", highlight=False)
        for line in problems:
            console.print(line, highlight=False, markup=False)
        console.print("[red]the decisions differ" if problems else "[green]the same decisions")
        code = 1 if problems else 0
    raise typer.Exit(code)


@app.command()
def view(
    file: Annotated[Path | None, typer.Argument(help="An MCAP recording [default: live, from the bus]")] = None,
    web: Annotated[bool, typer.Option("--web", help="Serve Rerun's web viewer instead of opening the native "
                                                    "one")] = False,
    web_port: Annotated[int, typer.Option(help="HTTP port of the web viewer")] = 9090,
    grpc_port: Annotated[int, typer.Option(help="Port of the Rerun data server the web viewer reads")] = 9876,
    host: Annotated[str, typer.Option(help="This machine's name as a browser elsewhere reaches it")] = "localhost",
    save: Annotated[Path | None, typer.Option(help="Write a Rerun file (.rrd) instead of showing a "
                                                   "viewer")] = None,
    robot: RobotOption = None,
    connect: ConnectOption = None,
) -> None:
    """The camera with the marks found, the robot as a stick figure, its joint angles, situation and posture
    over time, and what it heard, decided and said: in a Rerun viewer. Needs the `view` extra."""
    try:
        from services.cli import view as v
    except ImportError as exc:
        typer.echo(f"error: the viewer needs the rerun-sdk package: pip install 'hri-op2[view]' ({exc})",
                   err=True)
        raise typer.Exit(2) from None
    from services.cli.mcapfile import RecordingError, read_recording
    from services.runtime import run_service
    from services.viewer.scene import ViewLogger

    try:
        recorded = list(read_recording(file)) if file is not None else []
        rec, address = v.open_stream(v.Sink(web=web, web_port=web_port, grpc_port=grpc_port, host=host, save=save),
                                     file.name if file else "live")
    except (RecordingError, v.NoDisplay) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    if address:
        console.print(f"web viewer: {address}", highlight=False, soft_wrap=True)
    logger = ViewLogger(rec)
    code = 0
    if file is not None:
        console.print(f"{v.log_recording(recorded, logger)} message(s) drawn from {file}", highlight=False)
        if web:
            console.print("serving until Ctrl-C", highlight=False)
            code = _wait_for_signal()
    else:

        def live(ctx: ServiceContext) -> None:
            v.LiveFeed(ctx, logger)
            ctx.wait()

        code = run_service("view", live, robot=robot, connect=connect, identity=OBSERVER)
    rec.flush()
    rec.disconnect()
    raise typer.Exit(code)


def _wait_for_signal() -> int:
    """Block until Ctrl-C or SIGTERM."""
    stop = stop_on_signals()
    while not stop.wait(0.5):
        pass
    return 0


def _choice(enum: type, value: str, what: str):  # type: ignore[no-untyped-def]
    """`value` as a member of `enum`; the error lists every accepted value, 'none' included."""
    try:
        return enum(value)
    except ValueError:
        choices = ", ".join([*(e.value for e in enum), "none"])
        raise typer.BadParameter(f"unknown {what} {value!r}; choose from {choices}") from None


if __name__ == "__main__":
    app()
