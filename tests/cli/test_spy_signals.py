"""`hri spy` ends on Ctrl-C and on SIGTERM, closing its session, also when started from a script's
background job (which inherits SIGINT ignored, so Python raises no KeyboardInterrupt)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from queue import Empty

import pytest

from services.runtime import ServiceContext
from tests.conftest import ROOT, read_lines


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["sigint-ignored-at-start", "sigterm"])
def test_spy_stops_on_signal(sig: signal.Signals, router_endpoint: str, robot_id: str,
                             bus: ServiceContext) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("HRI_", "ZENOH_"))}
    spy = subprocess.Popen(
        [sys.executable, "-m", "services.cli", "spy", "--connect", router_endpoint, "--robot", robot_id],
        cwd=ROOT, env={**env, "COLUMNS": "200"}, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True, preexec_fn=_ignore_sigint,
    )
    lines, reader = read_lines(spy)
    try:
        # The spy is subscribed once it reports the test's own liveliness token (history=True).
        first = lines.get(timeout=30)
        assert "+ alive" in first and "tester" in first, first
        spy.send_signal(sig)
        code = spy.wait(timeout=15)
    except (Empty, subprocess.TimeoutExpired):
        spy.kill()
        spy.wait()
        raise
    reader.join(5)
    rest = "".join(lines.queue)
    assert code == 0, rest
    assert "Traceback" not in rest, rest
