"""Command-line options every service shares (typer), so `--help` reads the same everywhere."""

from __future__ import annotations

from typing import Annotated

import typer

RobotOption = Annotated[
    str | None,
    typer.Option("--robot", envvar="HRI_ROBOT", help="Robot id in the key prefix hri/<robot>/ [default: op2]"),
]
ConnectOption = Annotated[
    str | None,
    typer.Option(
        "--connect",
        help="Comma-separated zenoh endpoints, client mode (overrides ZENOH_CONFIG and HRI_ZENOH_CONNECT; "
        "default tcp/127.0.0.1:7447)",
    ),
]
