"""`bench/vision_bench.py` says what it measured: the detector settings a run changed (`--set`, as given) are in its
JSON and on its table's second line, so that a result file read later names its detector; a setting that does not
exist is refused before any frame is made."""

from __future__ import annotations

import json

import typer
from typer.testing import CliRunner

from bench import vision_bench


def _bench() -> typer.Typer:
    app = typer.Typer()
    app.command()(vision_bench.main)
    return app


def test_the_json_and_the_table_name_the_settings_a_run_changed() -> None:
    runner, app = CliRunner(), _bench()
    changed = json.loads(runner.invoke(app, ["--frames", "4", "--seed", "3", "--json", "--set", "split=",
                                             "--set", "card_rescue=0.97"]).stdout)
    assert changed["settings"] == ["split=", "card_rescue=0.97"]
    assert json.loads(runner.invoke(app, ["--frames", "4", "--seed", "3", "--json"]).stdout)["settings"] == []
    table = runner.invoke(app, ["--frames", "4", "--seed", "3", "--set", "split="]).stdout.splitlines()
    assert "detector settings: split=" in table[:3]
    assert "detector settings: the defaults" in runner.invoke(app, ["--frames", "4", "--seed", "3"]).stdout


def test_a_setting_that_does_not_exist_is_refused() -> None:
    result = CliRunner().invoke(_bench(), ["--frames", "4", "--seed", "3", "--set", "bogus=1"])
    assert result.exit_code != 0 and "bogus=1" in result.output


def test_without_leaves_a_kind_of_clutter_out_of_the_tuning_frames_only() -> None:
    runner, app = CliRunner(), _bench()
    run = json.loads(runner.invoke(app, ["--split", "tuning", "--frames", "4", "--seed", "3", "--json",
                                         "--without", "filled_triangle"]).stdout)
    assert run["without"] == ["filled_triangle"]
    unknown = runner.invoke(app, ["--split", "tuning", "--frames", "4", "--without", "roof"])
    assert unknown.exit_code == 2 and "roof" in unknown.output
    other = runner.invoke(app, ["--split", "heldout", "--frames", "4", "--without", "text"])
    assert other.exit_code == 2 and "tuning" in other.output
