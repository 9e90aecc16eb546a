"""`bench/vision_bench.py` says what it measured: the detector settings a run changed (`--set`, as given) are in its
JSON and on its table's second line, so that a result file read later names its detector; a setting that does not
exist is refused before any frame is made."""

from __future__ import annotations

import json

import pytest
import typer
from typer.testing import CliRunner

from bench import flicker, glare, vision_bench


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


def test_flicker_bands_cross_the_frame_in_rows_and_none_without_flicker() -> None:
    import numpy as np

    grey = np.full((480, 640, 3), 128, np.uint8)
    same, amplitude = flicker.flicker_bands(grey, np.random.default_rng(1), 0.0)
    assert amplitude == 0.0 and np.array_equal(same, grey)
    amplitudes = []
    for i in range(20):
        banded, amplitude = flicker.flicker_bands(grey, np.random.default_rng(i), 1.0)
        assert banded.shape == grey.shape and banded.dtype == np.uint8 and 0 < amplitude <= 1.0
        assert np.ptp(banded, axis=1).max() == 0  # each row one gain: bands, not blotches
        rows = banded[:, 0, 0].astype(int)
        expected = 128 * ((1 + amplitude) ** (1 / 2.2) - (1 - amplitude) ** (1 / 2.2))  # grey 128 is linear 0.22
        assert abs(rows.max() - rows.min() - expected) <= 0.25 * expected + 2  # brightest and darkest rows
        if amplitude > 0.1:
            assert 2 <= np.count_nonzero(np.diff(np.sign(rows - rows.mean())) != 0) <= 16  # 1.5-8 cycles a frame
        amplitudes.append(amplitude)
    assert max(amplitudes) > 0.6 and min(amplitudes) < 0.6  # the depth drawn per frame, and the exposure's share


def test_flicker_is_named_and_sliced_and_out_of_range_refused() -> None:
    runner, app = CliRunner(), _bench()
    run = json.loads(runner.invoke(app, ["--frames", "8", "--seed", "3", "--json", "--flicker", "0.5"]).stdout)
    assert run["flicker"] == 0.5 and sum(c["n"] for c in run["recall_by"]["flicker_amplitude"].values()) == 6
    table = runner.invoke(app, ["--frames", "4", "--seed", "3", "--flicker", "0.5"]).stdout
    assert "under flickering light through a rolling shutter, depth up to 0.5 (sine)" in table
    assert runner.invoke(app, ["--frames", "4", "--flicker", "1.5"]).exit_code == 2


def test_a_lamps_bands_move_on_from_frame_to_frame_as_its_phase_does() -> None:
    import numpy as np

    lamp = flicker.Lamp("sine", f=100.0, exposure=0.002, readout=0.03, depth=0.8, phase=0.0)
    first, next_frame, later = (lamp.gain(480, t) for t in (0.0, 1 / 30, 3 / 30))
    assert np.allclose(first, later)  # 100 Hz at 30 fps: a third of a cycle a frame, the same bands every third frame
    assert not np.allclose(first, next_frame)
    assert np.allclose(flicker.Lamp("sine", 120.0, 0.002, 0.03, 0.8, 0.0).gain(480, 1 / 30),
                       flicker.Lamp("sine", 120.0, 0.002, 0.03, 0.8, 0.0).gain(480, 0.0))  # 120 Hz: they stand still
    dimmer = flicker.Lamp("pwm", f=400.0, exposure=0.001, readout=0.03, depth=1.0, phase=0.0, duty=0.5)
    rows = dimmer.gain(480)
    assert abs(rows.mean() - 1.0) < 1e-9 and 0.5 < dimmer.amplitude() <= 1.0  # 12 thin bands, light half the time
    assert np.allclose(flicker.Lamp("sine", 100.0, 0.01, 0.03, 0.8, 0.0).gain(480), 1.0)  # a whole cycle's exposure


def test_a_highlight_adds_light_over_its_box_and_washes_its_middle_out() -> None:
    import numpy as np

    card = np.full((120, 160, 3), 200, np.uint8)
    card[50:70, 40:120] = 30  # a bar of dark ink
    box = (40, 50, 80, 20)
    for i in range(20):
        rng = np.random.default_rng(i)
        spot = glare.draw_highlight(rng, 2.0, 120, 160, box)
        assert 40 <= spot.centre[0] <= 120 and 50 <= spot.centre[1] <= 70  # within the mark's box
        assert 1.0 <= spot.peak <= 2.0 and spot.axes[1] <= spot.axes[0]
        light = spot.light(120, 160)
        lit = glare.glared(card, light)
        assert (lit >= card).all()  # a reflection only adds light
        cx, cy = round(spot.centre[0]), round(spot.centre[1])
        assert (lit[cy, cx] >= 240).all() and glare.washed_share(light, box) > 0  # its middle: ink about as white as paper
        far = light < 1e-6
        assert np.array_equal(lit[far], card[far])  # far from it, the frame as it was
    grey = glare.glared(card[:, :, 0], light)
    assert grey.shape == (120, 160) and np.array_equal(grey, lit[:, :, 0])
    assert glare.washed_share(np.zeros((120, 160), np.float32), box) == 0.0
    same, washed = glare.glare_spot(card, np.random.default_rng(0), 0.0, box)
    assert washed == 0.0 and np.array_equal(same, card)
    with pytest.raises(ValueError, match="peak"):
        glare.draw_highlight(np.random.default_rng(0), -1.0, 120, 160)


def test_glare_is_named_and_sliced_and_out_of_range_refused() -> None:
    runner, app = CliRunner(), _bench()
    run = json.loads(runner.invoke(app, ["--frames", "8", "--seed", "3", "--json", "--glare", "2"]).stdout)
    assert run["glare"] == 2.0 and sum(c["n"] for c in run["recall_by"]["glare_washed"].values()) == 6
    assert "glare_washed" not in json.loads(runner.invoke(app, ["--frames", "4", "--seed", "3", "--json"]).stdout)[
        "recall_by"]
    table = runner.invoke(app, ["--frames", "4", "--seed", "3", "--glare", "2"]).stdout
    assert "a lamp's reflection on a glossy card over every mark, its peak up to 2 of the sensor's white" in table
    assert runner.invoke(app, ["--frames", "4", "--glare", "-1"]).exit_code == 2
