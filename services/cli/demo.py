"""`hri demo`: the paper's experiment end to end on the simulated OP2.

Starts the embedded router and the five services (motion on the simulated bus, vision on its
synthetic scene, voice listening to a spool folder, speech writing WAV files), speaks each command
as synthesised audio, holds up each mark in front of the synthetic camera, prints a live timeline
and checks every outcome against the scenario. Exit status 0 means the robot behaved.
"""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from services.cli.record import McapRecorder
from services.cli.recorder import Event, describe
from services.cli.router import free_port
from services.cli.runner import StepResult
from services.cli.scenario import Scenario
from services.cli.simrobot import simulated_robot
from services.cli.utterance import DEFAULT_VOICE
from services.runtime import ServiceContext, configure_logging

MARKER = ".hri-demo"
"""The file that marks a folder as made by `hri demo`: only such a folder is ever cleared."""
RUN_OUTPUTS = ("state", "spool", "speech", "timeline.txt", "services.log", "keys")
"""What one run leaves in its output folder; the next run replaces these and nothing else."""


class OutputFolderError(ValueError):
    """`--out` names a folder the demo must not use; nothing was deleted."""


def prepare_out(out: Path) -> None:
    """Make `out` ready for a run: a fresh robot (no state, so no danger latched by an earlier run).

    Deletes only what an earlier demo run left there (`RUN_OUTPUTS`, in a folder with the marker);
    a non-empty folder the demo did not make is refused untouched.
    """
    if out.exists() and not out.is_dir():
        raise OutputFolderError(f"--out {out} is a file, not a folder; nothing was deleted")
    if out.is_dir() and not (out / MARKER).is_file() and any(out.iterdir()):
        raise OutputFolderError(f"--out {out} is not empty and was not made by `hri demo`; nothing was deleted: "
                                "choose a new or empty folder")
    for name in RUN_OUTPUTS:
        path = out / name
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        elif path.exists() or path.is_symlink():
            path.unlink()
    out.mkdir(parents=True, exist_ok=True)
    (out / MARKER).write_text("Made by `hri demo`. Each run replaces " + ", ".join(RUN_OUTPUTS) +
                              " here, and nothing else.\n")


_COLOURS = {"voice": "cyan", "vision": "magenta", "reasoner": "bold yellow", "motion": "green", "speech": "blue"}


class Timeline:
    """Prints events as they happen, and keeps a plain copy in a file."""

    def __init__(self, console: Console, path: Path) -> None:
        self.console = console
        self.t0 = time.monotonic()
        self._file = path.open("w")
        self._lock = threading.Lock()

    def event(self, e: Event) -> None:
        source, text = describe(e)
        self.line(e.t, source, escape(text))

    def line(self, t: float, source: str, text: str, style: str | None = None) -> None:
        stamp = f"{t - self.t0:7.2f}"
        with self._lock:
            self.console.print(f"{stamp}  [{style or _COLOURS.get(source, 'white')}]{source:<9}[/] {text}",
                               highlight=False, markup=True, soft_wrap=True)
            self._file.write(f"{stamp}  {source:<9} {Text.from_markup(text).plain}\n")
            self._file.flush()

    def close(self) -> None:
        self._file.close()


def summary(results: list[StepResult], title: str) -> Table:
    table = Table(title=title)
    for col in ("#", "step", "heard", "decision", "goals", "posture", "said", "check"):
        table.add_column(col, overflow="fold")
    for r in results:
        heard = (r.heard.command.value if r.heard and r.heard.command else ("-" if r.heard is None else "?"))
        dec = f"{r.decision.verdict.value} {r.decision.reason.value}" if r.decision else "-"
        if r.asked is not None:  # the robot asked back and the step's answer was said
            dec = f"ask {r.asked.reason.value}, answered: {dec}"
        goals = " ".join(g.action.value for g in r.goals) or "-"
        said = " ".join(f'"{t}"' for t in r.said) or "-"
        check = "[green]pass[/]" if r.ok else "[red]FAIL[/]"
        table.add_row(str(r.index), r.step.label(), heard, dec, goals,
                      r.posture.value if r.posture else "-", said, check)
    return table


def problems(results: list[StepResult]) -> list[str]:
    return [f"step {r.index} ({r.step.label()}): {'; '.join(r.problems)}" for r in results if not r.ok]


@contextmanager
def _recording(ctx: ServiceContext, path: Path | None, console: Console) -> Iterator[None]:
    """`hri demo --record FILE.mcap`: everything on the bus into FILE while the demo runs."""
    if path is None:
        yield
        return
    recorder = McapRecorder(ctx, path.resolve())
    try:
        yield
    finally:
        console.print(recorder.close().table())


def run_demo(scenario: Scenario, out: Path, *, port: int = 0, voice: str = DEFAULT_VOICE,
             console: Console | None = None, record: Path | None = None) -> int:
    """Run `scenario` on a fresh simulated robot whose files all live in `out` (its state in out/state).

    Raises `OutputFolderError` (before starting anything) for an `out` it must not use.
    """
    console = console or Console()
    out = out.resolve()
    prepare_out(out)
    configure_logging("warning")  # the timeline is the output; service logs go to services.log
    port = port or free_port()
    timeline = Timeline(console, out / "timeline.txt")
    console.rule(f"[bold]hri demo: {scenario.name}")
    if scenario.description:
        console.print(scenario.description.strip(), highlight=False)
    console.print(f"router tcp/127.0.0.1:{port}   output {out}   (watch live: HRI_KEYS_DIR={out / 'keys'} "
                  f"hri spy --connect tcp/127.0.0.1:{port})", highlight=False)
    results: list[StepResult] = []
    try:
        with simulated_robot(out, port=port, voice=voice, on_event=timeline.event) as robot, \
                _recording(robot.ctx, record, console):
            timeline.line(time.monotonic(), "demo", "waiting for the five services ...", "bold")
            missing = robot.runner.wait_ready()
            if missing:
                console.print(f"[red]the robot did not come up: no {', '.join(missing)}; see {robot.log_path}")
                return 2
            timeline.line(time.monotonic(), "demo", "robot ready", "bold")
            for i, step in enumerate(scenario.steps, 1):
                timeline.line(time.monotonic(), "demo", f"step {i}: {step.label()}", "bold white")
                result = robot.runner.run_step(i, step)
                results.append(result)
                mark = "[green]ok[/]" if result.ok else "[red]FAIL: " + "; ".join(result.problems) + "[/]"
                timeline.line(time.monotonic(), "demo", f"step {i} {step.label()}: {mark}", "bold")
    except KeyboardInterrupt:
        console.print("[yellow]interrupted")
        return 130
    finally:
        timeline.close()
    console.print(summary(results, f"{scenario.name}: {sum(r.ok for r in results)}/{len(results)} steps as expected"))
    for line in problems(results):
        console.print(f"[red]{line}", highlight=False)
    wavs = sorted((out / "speech").glob("*.wav")) if (out / "speech").exists() else []
    console.print(f"spoken replies: {len(wavs)} WAV file(s) in {out / 'speech'}; timeline in {out / 'timeline.txt'}; "
                  f"service logs in {out / 'services.log'}", highlight=False)
    passed = all(r.ok for r in results) and len(results) == len(scenario.steps)
    console.print("[bold green]The robot behaved as expected." if passed else "[bold red]The robot did not behave as expected.")
    return 0 if passed else 1
