"""Spool-folder latency of the voice service (prints figures; not a test).

Starts a zenoh router and the voice service (`watch:<tmp dir>`) as processes, then drops synthetic
command WAVs into the spool (atomic .tmp rename) and measures rename -> `VoiceCommand` received.

    .venv/bin/python bench/voice_latency.py --n 10
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from schemas.messages import VoiceCommand  # noqa: E402
from services.cli.rig import service_rig  # noqa: E402
from services.voice import synth  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10)
    args = ap.parse_args()
    spool = Path(tempfile.mkdtemp(prefix="voice-spool-"))
    got = threading.Event()
    received: list[float] = []

    def on_cmd(_msg: VoiceCommand) -> None:
        received.append(time.time())
        got.set()

    lat: list[float] = []
    try:
        with service_rig("bench", HRI_VOICE_SOURCE=f"watch:{spool}") as rig:
            rig.start("voice")
            rig.ctx.subscribe(rig.ctx.keys.voice_command, VoiceCommand, on_cmd)
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
        shutil.rmtree(spool, ignore_errors=True)
    a = np.array(lat) * 1000
    print(f"spool rename -> VoiceCommand received: n={a.size} p50={np.percentile(a, 50):.0f} ms "
          f"p90={np.percentile(a, 90):.0f} ms max={a.max():.0f} ms (50 ms poll; shared 2-core machine)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
