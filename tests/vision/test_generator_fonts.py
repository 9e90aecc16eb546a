"""The held-out and blind generators draw with fonts from the system: a machine without one of them draws other frames
from the same seed, and `bench/vision_bench.py` says so on its first line instead of reporting figures that cannot be
compared with the READMEs'."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from services.vision import blind, heldout


def test_missing_fonts_name_what_is_not_installed(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    there = tmp_path / "DejaVuSans.ttf"
    there.write_bytes(b"")
    monkeypatch.setattr(heldout, "FONT_FILES", (str(there), str(tmp_path / "Gone-Bold.ttf")))
    assert heldout.missing_fonts() == [str(tmp_path / "Gone-Bold.ttf")]
    monkeypatch.setattr(blind, "FONT_DIR", tmp_path)
    assert blind.missing_fonts() == [str(tmp_path / n) for n in blind.FONTS if n != "DejaVuSans.ttf"]


def test_a_missing_font_changes_the_frames_of_a_seed(monkeypatch: pytest.MonkeyPatch) -> None:
    """Why the bench must say it: the same seed, one font fewer, other frames."""
    if heldout.missing_fonts():
        pytest.skip(f"fonts missing here: {heldout.missing_fonts()}")
    frames = heldout.HeldOutGenerator(seed=5)
    first = [frames.frame(None)[0] for _ in range(6)]
    again = heldout.HeldOutGenerator(seed=5)
    assert all(np.array_equal(a, again.frame(None)[0]) for a in first)  # deterministic with the same fonts
    monkeypatch.setattr(heldout, "FONT_FILES", heldout.FONT_FILES[1:])
    fewer = heldout.HeldOutGenerator(seed=5)
    assert any(not np.array_equal(a, fewer.frame(None)[0]) for a in first)


def test_bench_says_its_frames_are_not_the_readmes_when_a_font_is_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    import typer

    from bench import vision_bench

    monkeypatch.setattr(heldout, "FONT_FILES", (*heldout.FONT_FILES, "/nonexistent/Gone-Bold.ttf"))
    app = typer.Typer()
    app.command()(vision_bench.main)
    out = CliRunner().invoke(app, ["--frames", "8", "--seed", "3"]).output
    assert "NOT the READMEs' frames for this seed: fonts missing" in out and "/nonexistent/Gone-Bold.ttf" in out
    monkeypatch.setattr(heldout, "FONT_FILES", tuple(f for f in heldout.FONT_FILES if "nonexistent" not in f))
    if not heldout.missing_fonts():
        assert "NOT the READMEs'" not in CliRunner().invoke(app, ["--frames", "8", "--seed", "3"]).output
