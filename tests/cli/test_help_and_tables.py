"""What a person reads: every help text whole, status values whole, scenario descriptions whole,
and error messages that list every accepted value."""

from __future__ import annotations

import importlib
import io
import re
from typing import Any

import pytest
import typer
from rich.console import Console
from typer.testing import CliRunner

from schemas import Health, HealthStatus
from services.cli import scenario as scenarios
from services.cli.main import app as hri_app
from services.cli.probe import status_table

APPS = ["services.cli.main", "services.vision.__main__", "services.voice.__main__", "services.reasoner.__main__",
        "services.motion.__main__", "services.motion.simbus.__main__", "services.speech.__main__"]


def _commands(cmd: Any, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], Any]]:
    """Every command of a (click) command tree, with the words that reach it."""
    found = [(path, cmd)]
    for name, sub in getattr(cmd, "commands", {}).items():
        found += _commands(sub, (*path, name))
    return found


def _squeeze(text: str) -> str:
    return re.sub(r"\s+", "", text)  # help is wrapped (even at hyphens) wherever the terminal needs


@pytest.mark.parametrize("module", APPS)
def test_bracketed_help_text_is_shown(module: str) -> None:
    """Rich markup would swallow "[default: op2]", "[env var: ...]" and the like."""
    app = importlib.import_module(module).app
    root = typer.main.get_command(app)
    for path, cmd in _commands(root):
        shown = _squeeze(CliRunner().invoke(app, [*path, "--help"], terminal_width=80).output)
        for param in cmd.params:
            for part in re.findall(r"\[[^\]]*\]", getattr(param, "help", None) or ""):
                assert _squeeze(part) in shown, f"{module} {' '.join(path)} {param.name}: {part} not shown"


def test_status_never_cuts_a_value() -> None:
    detail = {"sim_pid": 5988, "source": "synthetic:none", "fps": 9.87, "frames": 123456,
              "device": "/dev/serial/by-id/usb-ROBOTIS_OpenCM9.04-if00", "restored": "danger latched at 12:34:56"}
    health = Health(service="motion", status=HealthStatus.OK, uptime_s=1.0, detail=detail)
    console = Console(width=120, file=io.StringIO(), record=True)
    console.print(status_table({"motion": {"alive": True, "health": health}}, "op2"))
    rows = [line.split("│") for line in console.export_text().splitlines() if line.count("│") > 2]
    shown = _squeeze("".join(cells[-2] for cells in rows))  # the detail column, line after line
    for key, value in detail.items():
        assert _squeeze(f"{key}={value}") in shown


def test_demo_list_shows_whole_descriptions() -> None:
    out = CliRunner().invoke(hri_app, ["demo", "--list"])
    assert out.exit_code == 0
    shown = " ".join(out.output.split())
    for name in scenarios.builtin_names():
        assert f"{name} {' '.join(scenarios.load(name).description.split())}" in shown


@pytest.mark.parametrize(("args", "listed"), [(["send", "command", "dance"], "stop, why, none"),
                                              (["send", "mark", "square"], "TRIANGLE, none"),
                                              (["send", "scene", "square"], "TRIANGLE, none")])
def test_errors_list_none_among_the_values(args: list[str], listed: str) -> None:
    out = CliRunner().invoke(hri_app, args)
    assert out.exit_code == 2 and listed in " ".join(out.output.split())
