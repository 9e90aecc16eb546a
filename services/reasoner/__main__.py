"""`python -m services.reasoner`: run the reasoner service, or query a running one."""

from __future__ import annotations

import functools
import sys
from pathlib import Path
from typing import Annotated

import typer

from services.reasoner.service import NAME, ReasonerOptions, serve
from services.reasoner.soar_cli import query_soar
from services.runtime import run_service
from services.runtime.cli import ConnectOption, RobotOption

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

StateDirOption = Annotated[
    Path | None,
    typer.Option("--state-dir", help="Where the latched situation is kept (env HRI_STATE_DIR; "
                 "default $XDG_STATE_HOME/hri/<robot>)"),
]
KnowledgeOption = Annotated[
    Path | None,
    typer.Option("--knowledge", help="Semantic-memory file with the command knowledge and confidence "
                 "thresholds (env HRI_REASONER_KNOWLEDGE; default services/reasoner/agent/knowledge.soar)"),
]
DebuggerOption = Annotated[
    int | None,
    typer.Option("--debugger-port", help="Open the Soar kernel listener on this port for the Soar Java "
                 "debugger (env HRI_SOAR_DEBUGGER_PORT; default: no listener)"),
]


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    robot: RobotOption = None,
    connect: ConnectOption = None,
    state_dir: StateDirOption = None,
    knowledge: KnowledgeOption = None,
    debugger_port: DebuggerOption = None,
) -> None:
    """Run the reasoner service until SIGTERM or Ctrl-C."""
    ctx.obj = {"robot": robot, "connect": connect}
    if ctx.invoked_subcommand is not None:
        return
    try:
        options = ReasonerOptions.from_env(state_dir=state_dir, knowledge_file=knowledge,
                                           debugger_port=debugger_port)
    except ValueError as exc:
        typer.echo(f"reasoner: {exc}", err=True)
        raise typer.Exit(2) from None
    body = functools.partial(serve, options=options)
    raise typer.Exit(run_service(NAME, body, robot=robot, connect=connect))


@app.command()
def soar(
    ctx: typer.Context,
    command: Annotated[str, typer.Argument(help='A Soar command line, e.g. "print s1" or "stats"')],
    robot: RobotOption = None,
    connect: ConnectOption = None,
    timeout: Annotated[float, typer.Option(help="Seconds to wait for the reasoner's answer")] = 5.0,
) -> None:
    """Run a Soar command on the live agent of a running reasoner and print its output."""
    parent = ctx.obj or {}
    code, out, err = query_soar(command, robot=robot or parent.get("robot"),
                                connect=connect or parent.get("connect"), timeout=timeout)
    if out:
        sys.stdout.write(out if out.endswith("\n") else out + "\n")
    if err:
        sys.stderr.write(err if err.endswith("\n") else err + "\n")
    raise typer.Exit(code)


if __name__ == "__main__":
    app()
