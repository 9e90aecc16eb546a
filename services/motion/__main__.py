"""`python -m services.motion`: run the motion service."""

from __future__ import annotations

import typer

from services.runtime import run_service
from services.runtime.cli import ConnectOption, RobotOption
from services.motion.service import NAME, serve

app = typer.Typer(add_completion=False, help=__doc__)


@app.callback(invoke_without_command=True)
def main(ctx: typer.Context, robot: RobotOption = None, connect: ConnectOption = None) -> None:
    """Run the motion service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is None:
        raise typer.Exit(run_service(NAME, serve, robot=robot, connect=connect))


if __name__ == "__main__":
    app()
