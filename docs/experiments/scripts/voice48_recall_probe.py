"""Stop 88 (round voice48), the tuning-side look before the rule: does a canceller that recalls an earlier run's memory
of the robot's voice (`EchoCanceller.memory`, `recall`) hear more "stop"s said over the robot's first sentence than one
that starts cold?

`bench/voice_own.py --recall`'s streams (the "stop" over the first sentence of a run, through a room with the
loudspeaker 0.1 m away, a small loudspeaker's clipping, the sound card's delay and the state's error; the memory made
by the service's canceller over three other sentences through another room with the same loudspeaker, or the same
room), with espeak-ng's "stop"s only (the spotter's training family), never a held-out voice:

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice48_recall_probe.py
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench.voice_own import (  # noqa: E402
    agent_sentences,
    explanation_sentences,
    spoken,
    stop_over_recalled,
)
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice import synth  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402
from voice46_look_back_probe import VOICES  # noqa: E402  (round voice46's espeak-ng voices, the same "stop"s)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--peaks", default="-26,-12,-3")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mic-rate", type=int, default=48000)
    ap.add_argument("--repeat", type=int, default=2, help="each espeak-ng voice's \"stop\" this many times")
    args = ap.parse_args()
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory() as tmp:
        voices = [spoken(s, tts, Path(tmp)) for s in agent_sentences() + explanation_sentences()]
    rng = np.random.default_rng(args.seed)
    stops = [synth.speak("stop", v, int(rng.integers(130, 190))) for v in VOICES * args.repeat]
    engine = make_engine("spotter")
    for peak in (float(p) for p in args.peaks.split(",")):
        over = stop_over_recalled(engine, SegmenterConfig(), voices, stops, peak, -26.0, -70.0, args.mic_rate,
                                  (0.25, 0.6), np.random.default_rng(args.seed))
        print(f"{peak:+.0f} dBFS: {over}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
