"""Stop 86, a probe: would cancelling the robot's own voice with its played audio as the reference let a person's
"stop" through?

`bench/voice_own.py --over` found a held-out "stop" said over the robot's voice heard 8 / 3 / 2 times in 47 (at -26 /
-12 / -3 dBFS of the robot's voice), 40 of 47 alone. An echo canceller needs the signal the loudspeaker played. This
probe gives it that signal (the speech service's espeak-ng audio, as `voice_own.py` makes it) and asks how many
"stop"s the spotter then hears, with speexdsp's canceller (through `pyaec`, which bundles it), against none.

The echo path is made harder than a linear filter on purpose, as a small loudspeaker is: the played audio is delayed
by the sound card (20-60 ms, drawn per clip), bent by the loudspeaker (`tanh` soft clipping, drive drawn per clip),
and sent through an image-source room with the loudspeaker 0.1 m from the microphone (`voice_own.own_room`). The
person's "stop" (held-out seed's clean "stop"s, other voices and engines) comes straight at -26 dBFS peak, at a
random moment within the sentence; the room's hiss at -70 dBFS RMS. The canceller is given the reference from the
moment the robot began (as the service would know it from `speech/state`), not aligned to the echo.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice45_aec_probe.py --over 2281
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.signal import fftconvolve

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import WORDS, heldout_items  # noqa: E402
from bench.voice_levels import at_level  # noqa: E402
from bench.voice_own import agent_sentences, explanation_sentences, own_room, spoken  # noqa: E402
from bench.voice_room import responses, rt60_range  # noqa: E402
from bench.voice_walking import LEAD_S, stream  # noqa: E402
from schemas.messages import Command  # noqa: E402
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402

FRAME = 160


def cancel(mic: np.ndarray, ref: np.ndarray, filter_length: int, preprocess: bool) -> np.ndarray:
    """speexdsp's echo canceller over `mic` with `ref` (float, the same length), 10 ms frames."""
    from pyaec import Aec

    aec = Aec(FRAME, filter_length, SAMPLE_RATE, preprocess)
    m = np.round(np.clip(mic, -1, 1) * 32767).astype(np.int16)
    r = np.round(np.clip(ref, -1, 1) * 32767).astype(np.int16)
    out = np.zeros_like(m)
    for k in range(0, m.size - FRAME + 1, FRAME):
        out[k : k + FRAME] = aec.cancel_echo(m[k : k + FRAME].tolist(), r[k : k + FRAME].tolist())
    return out / 32768.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--over", type=int, required=True)
    ap.add_argument("--peaks", default="-26,-12,-3")
    ap.add_argument("--person", type=float, default=-26.0)
    ap.add_argument("--filter", type=int, default=4096, help="the canceller's filter, samples (16 kHz)")
    ap.add_argument("--preprocess", action="store_true", help="speex's residual echo suppression too")
    ap.add_argument("--drive", default="0.5,2.0", help="the loudspeaker's tanh drive's range (0: linear)")
    ap.add_argument("--rt60", default="0.25,0.6")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=int, default=0)
    ap.add_argument("--warm", type=int, default=0, help="sentences said through the same room before each")
    args = ap.parse_args()
    lo, hi = (float(v) for v in args.drive.split(","))
    rt60 = rt60_range(args.rt60)
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory(prefix="hri-aec-") as tmp:
        dry = [spoken(s, tts, Path(tmp)) for s in agent_sentences() + explanation_sentences()]
    stops = [np.frombuffer(it.pcm, "<i2") / 32768.0 for it in heldout_items(args.over, 2)
             if it.label == WORDS.index("stop") and it.condition == "clean" and it.family != "noise"]
    if args.limit:
        stops = stops[: args.limit]
    engine, config = make_engine("spotter"), SegmenterConfig()
    lead = int(LEAD_S * SAMPLE_RATE)
    for peak in [float(p) for p in args.peaks.split(",")]:
        rng = np.random.default_rng(args.seed)
        heard = {"none": 0, "cancelled": 0}
        residual: list[float] = []
        for k, stop in enumerate(stops):
            # `--warm` sentences before it through the same echo path: the canceller runs on, as in a service
            ref = np.concatenate([dry[(k + j) % len(dry)] for j in range(args.warm, 0, -1)] + [dry[k % len(dry)]]) * 0.5
            spoken_from = ref.size - dry[k % len(dry)].size
            drive = rng.uniform(lo, hi)
            bent = np.tanh(drive * ref) / np.tanh(drive) if drive > 0 else ref
            delay = int(rng.uniform(0.02, 0.06) * SAMPLE_RATE)
            echo = fftconvolve(np.concatenate([np.zeros(delay), bent]), responses(own_room(rng, rt60))[0])
            scale = 10 ** (peak / 20) / (np.max(np.abs(echo)) + 1e-12)
            stop = at_level(stop, args.person)
            last = dry[k % len(dry)].size / SAMPLE_RATE
            at = spoken_from + int(rng.uniform(0.2, max(0.3, last - 0.3)) * SAMPLE_RATE)
            n = lead + max(echo.size, at + stop.size) + int(0.5 * SAMPLE_RATE)
            mic = rng.normal(0.0, 10 ** (-70 / 20), n)
            mic[lead : lead + echo.size] += echo * scale
            mic[lead + at : lead + at + stop.size] += stop
            reference = np.zeros(n)
            reference[lead : lead + ref.size] = ref
            mic = np.clip(mic, -1.0, 1.0)
            out = cancel(mic, reference, args.filter, args.preprocess)
            voiced = slice(lead + spoken_from, lead + ref.size)
            before = float(np.sum(mic[voiced] ** 2))
            after = float(np.sum(out[voiced] ** 2))
            residual.append(10 * np.log10(after / before + 1e-12))
            begin, end = LEAD_S + at / SAMPLE_RATE, LEAD_S + (at + stop.size) / SAMPLE_RATE
            for name, x in (("none", mic), ("cancelled", out)):
                segs = stream(engine, x, config)
                heard[name] += any(cmd is Command.STOP and s < end and e > begin for _, s, e, cmd, _ in segs)
        print(f"robot {peak:+.0f} dBFS: stop heard {heard['none']}/{len(stops)} without, {heard['cancelled']}/"
              f"{len(stops)} cancelled; energy over the sentence after/before p50 {np.median(residual):+.1f} dB",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
