"""Spool-folder latency of the voice service (prints figures; not a test).

Starts a zenoh router and the voice service (`watch:<tmp dir>`) as processes, then drops synthetic
command WAVs into the spool (atomic .tmp rename) and measures rename -> `VoiceCommand` received.

    .venv/bin/python bench/voice_latency.py --n 10
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import zenoh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from schemas.keys import Keys  # noqa: E402
from schemas.messages import VoiceCommand  # noqa: E402
from services.cli.router import free_port  # noqa: E402
from services.runtime import ServiceContext, client_config  # noqa: E402
from services.voice import synth  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10)
    args = ap.parse_args()
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    router = subprocess.Popen([sys.executable, "-m", "services.cli.router", "--port", str(port)], cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    spool = Path(tempfile.mkdtemp(prefix="voice-spool-"))
    env = dict(os.environ, HRI_ZENOH_CONNECT=endpoint, HRI_ROBOT="bench", HRI_VOICE_SOURCE=f"watch:{spool}")
    env.pop("ZENOH_CONFIG", None)
    time.sleep(1.0)
    voice = subprocess.Popen([sys.executable, "-m", "services.voice"], cwd=ROOT, env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    ctx = ServiceContext("bench", zenoh.open(client_config([endpoint])), Keys("bench"))
    got = threading.Event()
    received: list[float] = []

    def on_cmd(_msg: VoiceCommand) -> None:
        received.append(time.time())
        got.set()

    lat: list[float] = []
    try:
        ctx.subscribe(ctx.keys.voice_command, VoiceCommand, on_cmd)
        words = ["stop", "stand", "yes", "no", "down"]
        # warm-up: the service must be up and its engine loaded
        warm = synth.speech_clip("stop", "en-us", 150)
        deadline = time.time() + 60
        while not got.is_set() and time.time() < deadline:
            tmp = spool / "warm.wav.tmp"
            tmp.write_bytes(warm.path.read_bytes())
            tmp.replace(spool / f"warm-{time.time_ns()}.wav")
            got.wait(2.0)
        for i in range(args.n):
            clip = synth.speech_clip(words[i % len(words)], "en-us", 150)
            got.clear()
            tmp = spool / f"{i}.wav.tmp"
            tmp.write_bytes(clip.path.read_bytes())
            t0 = time.time()
            tmp.replace(spool / f"{i}.wav")
            if got.wait(10.0):
                lat.append(received[-1] - t0)
            time.sleep(0.1)
    finally:
        ctx.close()
        voice.send_signal(signal.SIGTERM)
        voice.wait(15)
        router.send_signal(signal.SIGTERM)
        router.wait(10)
        shutil.rmtree(spool, ignore_errors=True)
    a = np.array(lat) * 1000
    print(f"spool rename -> VoiceCommand received: n={a.size} p50={np.percentile(a, 50):.0f} ms "
          f"p90={np.percentile(a, 90):.0f} ms max={a.max():.0f} ms (50 ms poll; shared 2-core machine)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
