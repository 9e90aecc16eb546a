"""The probing tools on a secured bus: `hri record` subscribes as the deployment's observer and
`hri replay` publishes as its operator (the access rules would drop anyone else)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from services.cli.mcapfile import read_recording
from tests.conftest import ROOT
from tests.system.conftest import Robot

pytestmark = pytest.mark.system


def _hri(robot: Robot, *args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "HRI_KEYS_DIR": str(robot.out / "keys")}
    env.pop("HRI_CREDENTIALS", None)
    return subprocess.run([sys.executable, "-m", "services.cli", *args, "--robot", robot.ctx.keys.robot,
                           "--connect", robot.launcher.endpoint], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout, env=env)


def test_record_and_replay_run_as_the_observer_and_the_operator(robot: Robot) -> None:
    path = robot.out / "secured.mcap"
    done = _hri(robot, "record", str(path), "--duration", "2")
    assert done.returncode == 0, done.stdout + done.stderr
    keys = {m.key.rsplit("/", 2)[-2] + "/" + m.key.rsplit("/", 1)[-1] for m in read_recording(path)}
    assert {"motion/state", "vision/marks"} <= keys, keys  # the observer may read what the services put
    replayed = _hri(robot, "replay", str(path), "--rate", "0")
    assert replayed.returncode == 0, replayed.stdout + replayed.stderr
    assert "replayed" in replayed.stdout
