"""`hri demo --out`: never deletes what the demo did not create, and each run starts with its own state."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from services.cli.demo import MARKER, RUN_OUTPUTS, OutputFolderError, prepare_out
from services.cli.simrobot import simulated_env
from tests.conftest import ROOT


def _tree(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def test_a_new_folder_is_made_and_marked(tmp_path: Path) -> None:
    out = tmp_path / "a" / "demo"
    prepare_out(out)
    assert (out / MARKER).is_file()
    prepare_out(tmp_path / "empty-but-there")  # an empty folder is fine too
    assert (tmp_path / "empty-but-there" / MARKER).is_file()


def test_a_folder_the_demo_did_not_make_is_refused_untouched(tmp_path: Path) -> None:
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "main.py").write_text("precious")
    (tmp_path / "state").mkdir()  # even names the demo uses are not the demo's here
    (tmp_path / "timeline.txt").write_text("mine")
    before = _tree(tmp_path)
    with pytest.raises(OutputFolderError, match="not made by `hri demo`; nothing was deleted"):
        prepare_out(tmp_path)
    assert _tree(tmp_path) == before and (tmp_path / "src" / "main.py").read_text() == "precious"


def test_a_file_is_refused(tmp_path: Path) -> None:
    f = tmp_path / "notes.txt"
    f.write_text("keep")
    with pytest.raises(OutputFolderError, match="is a file"):
        prepare_out(f)
    assert f.read_text() == "keep"


def test_a_demo_folder_loses_only_the_last_run_and_its_latched_state(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    prepare_out(out)
    for name in RUN_OUTPUTS:  # what a run leaves, the state with a danger latched in it among them
        if "." in name:
            (out / name).write_text("old run")
        else:
            (out / name).mkdir()
            (out / name / "old.bin").write_text("old run")
    (out / "my-notes.md").write_text("mine")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "keep.wav").write_text("mine")
    (out / "speech").rename(out / "speech-old")
    (out / "speech").symlink_to(elsewhere)  # a link is removed, never followed
    prepare_out(out)
    assert _tree(out) == {MARKER, "my-notes.md", "speech-old", "speech-old/old.bin"}
    assert (elsewhere / "keep.wav").read_text() == "mine"


def test_the_demo_robot_keeps_its_state_in_its_own_folder(tmp_path: Path) -> None:
    """Not the per-user default (~/.local/state/hri/<robot>) that every checkout would share."""
    env = simulated_env(tmp_path)
    assert Path(env["HRI_STATE_DIR"]) == tmp_path / "state"
    assert "state" in RUN_OUTPUTS  # so each run starts without a danger latched by the last one


def test_hri_demo_out_dot_deletes_nothing(tmp_path: Path) -> None:
    (tmp_path / "checkout.txt").write_text("precious")
    out = subprocess.run([sys.executable, "-m", "services.cli", "demo", "--out", "."], cwd=tmp_path,
                         capture_output=True, text=True, timeout=60,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("\n") == 1 and "nothing was deleted" in out.stderr
    assert _tree(tmp_path) == {"checkout.txt"}
