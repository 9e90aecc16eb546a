"""Stop 87 (round voice46), the tuning-side look before the rule: does holding the stream back while the echo
canceller looks for a sentence's echo (`EchoCanceller.look_back`) hear the "stop"s said over a sentence's start?

`bench/voice_own.py --cancel`'s streams (a room with the loudspeaker 0.1 m away, a small loudspeaker's clipping, the
sound card's delay and the state's error per sentence; the "stop" over the last of four sentences), with espeak-ng's
"stop"s only (the spotter's training family), never a held-out voice:

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice46_look_back_probe.py
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from bench.voice_own import agent_sentences, explanation_sentences, spoken, stop_over_cancelled  # noqa: E402
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice import synth  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402

VOICES = ("en", "en-us", "en-gb", "en+m3", "en+f2", "en+f4", "en-us+m7", "en-us+f3", "en-gb+m1", "en-gb+f1",
          "en+croak", "en+whisper")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--peaks", default="-26,-12,-3")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mic-rate", type=int, default=48000)
    ap.add_argument("--warm", type=int, default=3, help="sentences before the one the \"stop\" is said over")
    args = ap.parse_args()
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory() as tmp:
        voices = [spoken(s, tts, Path(tmp)) for s in agent_sentences() + explanation_sentences()]
    rng = np.random.default_rng(args.seed)
    stops = [synth.speak("stop", v, int(rng.integers(130, 190))) for v in VOICES]
    engine = make_engine("spotter")
    for peak in (float(p) for p in args.peaks.split(",")):
        over = stop_over_cancelled(engine, SegmenterConfig(), voices, stops, peak, -26.0, -70.0, args.mic_rate,
                                   (0.25, 0.6), np.random.default_rng(args.seed), warm=args.warm)
        print(f"{peak:+.0f} dBFS: {over}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
