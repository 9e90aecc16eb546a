"""Scenario files: the built-in ones load, bad ones are refused with a message naming the problem."""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from rich.console import Console

from schemas import Shape
from services.cli import scenario as scenario_module
from services.cli.demo import MARKER, run_demo
from services.cli.scenario import ScenarioError, builtin_names, load
from tests.conftest import ROOT


def test_builtin_scenarios_load() -> None:
    assert {"paper", "danger"} <= set(builtin_names())
    paper = load("paper")
    labels = [s.label() for s in paper.steps]
    assert labels[0] == 'say "stand"' and labels[-1] == 'say "down"'
    assert [s.shape for s in paper.steps if s.show] == [Shape.X, None, Shape.O, None]
    assert sum(s.say == "go" for s in paper.steps) == 2
    for name in ("paper", "danger"):  # every command is spoken through the recogniser, "go" included
        assert not [s for s in load(name).steps if s.send is not None]


def test_a_scenario_file_by_path(tmp_path: Path) -> None:
    f = tmp_path / "mine.yaml"
    f.write_text("name: mine\nsteps:\n  - say: stand\n    expect: {verdict: obey, posture: standing}\n  - wait: 1\n")
    s = load(f)
    assert s.name == "mine" and s.steps[0].expect.posture.value == "standing" and s.steps[1].wait == 1


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("name: x\nsteps: []\n", "steps"),
        ("name: x\nsteps:\n  - say: stand\n    show: X\n", "exactly one of say, send, show, wait"),
        ("name: x\nsteps:\n  - show: SQUARE\n", "show must be X, O, TRIANGLE or none"),
        ("name: x\nsteps:\n  - send: dance\n", "step 1, send:"),
        ("name: x\nsteps:\n  - say: stand\n  - say: go\n    show: X\n", "step 2: Value error"),
        ("name: x\nsteps:\n  - say: go\n    expect: {verdict: maybe}\n", "verdict"),
        ("name: x\nsteps:\n  - say: go\n    expect: {colour: red}\n", "colour"),
        ("name: x\nsteps:\n  - wait: 1\n    expect: {verdict: obey}\n", "a wait step can only expect"),
        ("name: [unclosed\n", "not valid YAML"),
        ("name: x\nsteps:\n  - wait: 1\n    confirm: \"yes\"\n", "confirm needs words, and a say or show step"),
        ("name: x\nsteps:\n  - say: go\n    confirm: \" \"\n", "confirm needs words"),
    ],
)
def test_bad_scenarios_are_refused_clearly(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ScenarioError, match="bad.yaml") as err:
        load(f)
    assert message in str(err.value)


def test_unknown_scenario_names_the_choices() -> None:
    with pytest.raises(ScenarioError, match="paper"):
        load("no-such-scenario")


def test_demo_refuses_a_bad_scenario_before_starting_anything(tmp_path: Path) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text("name: x\nsteps:\n  - show: SQUARE\n")
    out = subprocess.run([sys.executable, "-m", "services.cli", "demo", "--scenario", str(f), "--out",
                          str(tmp_path / "out")], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and "show must be" in out.stderr
    assert not (tmp_path / "out").exists()


def _module_example(tmp_path: Path) -> Path:
    """The YAML example in the scenario module's docstring, as a file."""
    block = scenario_module.__doc__.split("\n\n")[1]
    f = tmp_path / "example.yaml"
    f.write_text(textwrap.dedent(block))
    return f


def test_the_module_example_is_a_valid_scenario(tmp_path: Path) -> None:
    example = load(_module_example(tmp_path))
    assert [s.label() for s in example.steps] == ['say "stand"', 'say "go" (if asked: "yes")', "show X", "wait 1 s",
                                                  "send go"]
    assert example.name not in builtin_names()


@pytest.mark.system
def test_the_module_example_passes_on_the_simulated_robot(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    code = run_demo(load(_module_example(tmp_path)), out, console=Console(file=io.StringIO(), width=120))
    timeline = (out / "timeline.txt").read_text()
    assert code == 0, timeline
    assert "step 1: say" in timeline and "step 5: send go" in timeline  # counted from 1, as errors are
    assert (out / MARKER).is_file() and (out / "state").is_dir()  # the demo's own state folder
    assert list((out / "speech").glob("*.wav"))  # "Sorry, I cannot do it." was spoken
