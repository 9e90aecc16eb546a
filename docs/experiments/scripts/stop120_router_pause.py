"""Does the router's input limit drop commands sent 30 ms apart that reach it together?

A secured router for robot `sec` (`python -m services.cli.router`, with `schemas.access.RATE_LIMITS`), a `voice`
session putting "yes", "no", "yes" on `voice/command` 30 ms apart and a `reasoner` session counting what arrives;
in alternate trials the router process is paused (SIGSTOP) for 200 ms while the three are put, as a loaded
machine's scheduler may hold it back. Stop 120: paused 1 of 3 arrive (twice), not paused 3 of 3.

    .venv/bin/python docs/experiments/scripts/stop120_router_pause.py
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import zenoh

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from schemas.keys import Keys  # noqa: E402
from services.cli import keys as deployment_keys  # noqa: E402
from services.runtime import Credentials, client_config  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def main() -> None:
    keys_dir = Path(tempfile.mkdtemp()) / "keys"
    deployment_keys.init(keys_dir)
    port = free_port()
    router = subprocess.Popen([sys.executable, "-m", "services.cli.router", "--keys-dir", str(keys_dir), "--robot",
                               "sec", "--listen", f"tcp/127.0.0.1:{port}"], cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(3)
    endpoint = f"tcp/127.0.0.1:{port}"
    reasoner, voice = (zenoh.open(client_config([endpoint], Credentials.load(keys_dir / n)))
                       for n in ("reasoner", "voice"))
    key = Keys("sec").voice_command
    got: list[bytes] = []
    _sub = reasoner.declare_subscriber(key, lambda s: got.append(bytes(s.payload)))
    pub = voice.declare_publisher(key)
    time.sleep(1)
    try:
        for paused in (False, True, False, True):
            got.clear()
            if paused:
                os.kill(router.pid, signal.SIGSTOP)
            for word in (b"yes", b"no", b"yes"):
                pub.put(word)
                time.sleep(0.03)
            if paused:
                time.sleep(0.2)
                os.kill(router.pid, signal.SIGCONT)
            time.sleep(1.0)
            print(f"router paused {paused}: 3 put 30 ms apart, {len(got)} arrived: {got}", flush=True)
    finally:
        reasoner.close()
        voice.close()
        router.terminate()
        router.wait()


if __name__ == "__main__":
    main()
