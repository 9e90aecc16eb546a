"""`./run`: its help is its header comment (not its source), and an unknown subcommand fails."""

from __future__ import annotations

import subprocess

from tests.conftest import ROOT


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["bash", str(ROOT / "run"), *args], capture_output=True, text=True, timeout=30)


def test_help_is_the_header_comment_only() -> None:
    header = []
    for line in (ROOT / "run").read_text().splitlines()[1:]:
        if not line.startswith("#"):
            break
        header.append(line[2:] if line.startswith("# ") else line[1:])
    for args in ([], ["help"], ["--help"]):
        out = run(*args)
        assert out.returncode == 0 and out.stdout.splitlines() == header
    assert "./run demo" in out.stdout and "set -euo" not in out.stdout and 'cd "$(dirname' not in out.stdout


def test_an_unknown_subcommand_exits_2_with_the_help_on_stderr() -> None:
    out = run("tset")
    assert out.returncode == 2 and out.stdout == ""
    assert "unknown command 'tset'" in out.stderr and "./run tests" in out.stderr
