"""What the echo canceller's fit costs the voice service while it listens (prints figures; not a test).

Each time the robot falls silent the canceller fits the way from its loudspeaker to its microphone again
(`services/voice/echo_fit.py`, round voice49) on a thread of its own, while the service's stream thread and the
microphone's PortAudio callback (Python code, every `mic.CHUNK_S`: 30 ms) go on. Python runs one thread at a time; a
compiled call that keeps the interpreter's lock stops all the others for as long as it lasts. This bench makes echo
memories as `voice_own.py --recall` makes them (three of the robot's sentences through an `EchoPath` drawn for each, at
the loudspeaker volume that brings the robot's voice to `--peak` dBFS at the microphone, in a quiet room) and fits each
with each of `SOLVERS` while a thread standing in for the PortAudio callback asks to wake every 30 ms, and prints per
solver: the fit's time, how late that thread woke (worst, p99), and how far the solvers' impulse responses differ; then
the same for the whole refit as the service makes it (`EchoCanceller.recall`: the fit and a new speexdsp filter taught
the memory through it), and for nothing running at all (the machine's own lateness).

    .venv/bin/python bench/voice_echo_fit.py
    .venv/bin/python bench/voice_echo_fit.py --memories 10 --peak -3 --json out.json
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

import numpy as np
import scipy.linalg

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_own import EchoPath, agent_sentences, echo_memory, spoken  # noqa: E402
from bench.voice_room import rt60_range  # noqa: E402
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.echo import EchoCanceller, Played  # noqa: E402
from services.voice.echo_fit import fit_path, solve_toeplitz  # noqa: E402
from services.voice.mic import CHUNK_S  # noqa: E402

SOLVERS: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "scipy.linalg.solve_toeplitz": scipy.linalg.solve_toeplitz,
    "echo_fit.solve_toeplitz": solve_toeplitz,
}


T = TypeVar("T")


def lateness(work: Callable[[], T], period: float = CHUNK_S) -> tuple[float, list[float], T]:
    """`work()` run on a thread of its own while this one asks to wake every `period` s: how long the work took (s),
    how late each wake-up was (s), and what the work returned."""
    late: list[float] = []
    took: list[float] = []
    result: list[T] = []

    def run() -> None:
        began = time.perf_counter()
        result.append(work())
        took.append(time.perf_counter() - began)

    worker = threading.Thread(target=run, name="bench-work")
    due = time.perf_counter() + period
    worker.start()
    while worker.is_alive():
        time.sleep(max(0.0, due - time.perf_counter()))
        now = time.perf_counter()
        late.append(now - due)
        due = max(due + period, now)  # a late wake-up does not make the next ones late
    worker.join()
    return took[0], late, result[0]


def measured(works: Iterable[Callable[[], T]]) -> tuple[dict[str, float], list[T]]:
    """Each of `works` run through `lateness` in turn: the figures over all of them, and what each returned."""
    took: list[float] = []
    late: list[float] = []
    results: list[T] = []
    for work in works:
        t, w, result = lateness(work)
        took.append(t)
        late += w
        results.append(result)
    return {"ms_median": round(float(np.median(took)) * 1e3, 1), "ms_max": round(max(took) * 1e3, 1),
            "late_ms_max": round(max(late) * 1e3, 1), "late_ms_p99": round(float(np.percentile(late, 99)) * 1e3, 1),
            "wakes": len(late)}, results


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--memories", type=int, default=6, help="echo memories made and fitted")
    ap.add_argument("--peak", type=float, default=-12.0, help="the robot's voice at its own microphone, dBFS peak")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss through the microphone, dBFS RMS")
    ap.add_argument("--rt60", default="0.25,0.6", help="the rooms' reverberation time's range (Sabine), s")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    try:
        rt60 = rt60_range(args.rt60)
    except ValueError as exc:
        ap.error(str(exc))
    rng = np.random.default_rng(args.seed)
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory(prefix="hri-echo-fit-") as tmp:
        voices = [spoken(s, tts, Path(tmp)) for s in agent_sentences()]
    memories = []
    for _ in range(args.memories):
        path = EchoPath.draw(rng, rt60)
        said = [voices[i] for i in rng.choice(len(voices), 3, replace=False)]
        scale = 10 ** (args.peak / 20) / (max(path.peak(v) for v in said) + 1e-12)
        memories.append(echo_memory(said, path, scale, args.floor, None, rng, 1000.0))
    rows: dict[str, dict[str, float]] = {}
    fits: dict[str, list[np.ndarray]] = {}
    for name, solve in SOLVERS.items():
        rows[name], found = measured(lambda mic=mic, ref=ref, solve=solve: fit_path(mic, ref, SAMPLE_RATE, solve=solve)
                                     for mic, ref in memories)
        fits[name] = [f[0] for f in found if f is not None]
        rows[name]["fitted"] = len(fits[name])
    rows["EchoCanceller.recall (the service's refit)"], _ = measured(
        lambda mic=mic, ref=ref: EchoCanceller(Played(), fit=True).recall(mic, ref) for mic, ref in memories)
    rows["nothing (time.sleep)"], _ = measured(lambda: time.sleep(0.3) for _ in memories)
    a, b = fits.values()
    differ = max((float(np.max(np.abs(x - y)) / np.max(np.abs(x))) for x, y in zip(a, b, strict=True)), default=0.0)
    print(f"{args.memories} echo memories of 3 sentences at {args.peak:.0f} dBFS; a thread asking to wake every "
          f"{CHUNK_S * 1e3:.0f} ms meanwhile")
    print(f"{'':44} {'fit ms':>14} {'woke late ms':>16} {'wakes':>6}")
    print(f"{'':44} {'median':>7}{'max':>7} {'max':>8}{'p99':>8}")
    for name, r in rows.items():
        print(f"{name:44} {r['ms_median']:7.1f}{r['ms_max']:7.1f} {r['late_ms_max']:8.1f}{r['late_ms_p99']:8.1f} "
              f"{r['wakes']:6d}")
    print(f"the solvers' impulse responses differ by at most {differ:.1e} of their peak "
          f"({len(a)} of {args.memories} memories fitted)")
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "max_relative_difference": differ}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
