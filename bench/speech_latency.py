"""Speech latency: from a request received to its audio ready, for a short reply.

Two measurements:
  synth   espeak-ng alone, in this process: text in, complete WAV file in place (the service's code path).
  bus     the speech service as a process on a loopback Zenoh router: the publisher's `put` of a
          SpeechRequest to the arrival of SpeechState(speaking=True) (audio ready, state sent), and the
          service's own figure (request received -> WAV ready) from its Health detail.
Requests on the bus are sent one after another, each after the previous utterance ended, so no
request waits in the queue. Figures are noisy on a shared 2-core machine.

    .venv/bin/python bench/speech_latency.py [--text "Sorry, I cannot do it."] [--n 15] [--synth-n 50]
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from schemas.messages import SpeechRequest, SpeechState  # noqa: E402
from services.cli.rig import service_rig  # noqa: E402
from services.speech.config import SpeechConfig  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402


def stats(ms: list[float]) -> dict[str, float]:
    a = np.array(ms)
    return {"n": len(a), "p50_ms": round(float(np.percentile(a, 50)), 1),
            "p95_ms": round(float(np.percentile(a, 95)), 1), "max_ms": round(float(a.max()), 1)}


def bench_synth(text: str, n: int) -> dict[str, float]:
    c = SpeechConfig()
    tts = EspeakNg(c.voice, c.rate, c.volume)
    with tempfile.TemporaryDirectory() as tmp:
        tts.synthesize(text, Path(tmp) / "warm.wav")
        times = [tts.synthesize(text, Path(tmp) / f"{i}.wav").synth_s * 1000 for i in range(n)]
        duration = tts.synthesize(text, Path(tmp) / "d.wav").duration_s
    return {**stats(times), "audio_s": round(duration, 3)}


def bench_bus(text: str, n: int) -> dict[str, object]:
    tmp = Path(tempfile.mkdtemp(prefix="speech-bench-"))
    log_path = tmp / "speech.log"
    with open(log_path, "wb") as log, service_rig(f"bench{os.getpid()}", HRI_SPEECH_OUT=str(tmp)) as rig:
        ctx = rig.ctx
        events: dict[tuple[str | None, bool], float] = {}
        cond = threading.Condition()

        def on_state(msg: SpeechState) -> None:
            with cond:
                events[(msg.id, msg.speaking)] = time.perf_counter()
                cond.notify_all()

        def wait_event(key: tuple[str | None, bool], timeout: float = 20.0) -> float:
            with cond:
                if not cond.wait_for(lambda: key in events, timeout):
                    raise RuntimeError(f"no SpeechState {key} within {timeout} s; see {log_path}")
                return events[key]

        ctx.subscribe(ctx.keys.speech_state, SpeechState, on_state)
        rig.start("speech", output=log)
        wait_event((None, False), timeout=30)
        pub = ctx.publisher(ctx.keys.speech_say, SpeechRequest)
        e2e: list[float] = []
        for i in range(n + 1):  # the first is a warm-up
            t0 = time.perf_counter()
            pub.put(SpeechRequest(id=f"b{i}", text=text))
            started = wait_event((f"b{i}", True))
            wait_event((f"b{i}", False))
            if i:
                e2e.append((started - t0) * 1000)
        health = ctx.query_health("speech")
    shutil.rmtree(tmp, ignore_errors=True)  # kept above, with the service log, only when a step failed
    detail = health.detail if health else {}
    return {
        "request_put_to_speaking_state": stats(e2e),
        "service_received_to_audio_ready": {k: detail.get(k) for k in ("ready_ms_p50", "ready_ms_p95")}
        | {"spoken": detail.get("spoken")},
    }


def main(
    text: Annotated[str, typer.Option(help="The short reply to time")] = "Sorry, I cannot do it.",
    n: Annotated[int, typer.Option(min=1, help="Requests over the bus (each waits for the previous)")] = 15,
    synth_n: Annotated[int, typer.Option(min=1, help="In-process syntheses")] = 50,
) -> None:
    result = {
        "text": text,
        "cpus": os.cpu_count(),
        "load_avg_1m": round(os.getloadavg()[0], 2),
        "synth": bench_synth(text, synth_n),
        "bus": bench_bus(text, n),
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    typer.run(main)
