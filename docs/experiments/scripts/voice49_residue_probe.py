"""Stop 89 (round voice49), the tuning-side look before the rule: how much of the robot's voice must the canceller take
away for a person's "stop" to be heard over it, and does another canceller (WebRTC's AEC3) take more?

`bench/voice_own.py --recall`'s streams (the "stop" over the robot's first sentence of a run, through a room with the
loudspeaker 0.1 m away and a small loudspeaker's clipping; espeak-ng's "stop"s only, the spotter's training family,
never a held-out voice), heard: without the canceller; with the service's canceller cold, and having recalled the
memory of three sentences through the same room; and with the robot's voice left in at -20, -30 and -40 dB of itself
(the residue of a canceller that takes that much away and does nothing else) or taken out whole:

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice49_residue_probe.py

`--webrtc` hears the same streams through WebRTC's audio processing module (AEC3, its residual echo suppressor
included; LiveKit's Python wheel, `pip install livekit==1.2.1`, not a dependency of this project) in place of
speexdsp, cold and recalled.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import services.voice.echo as echo  # noqa: E402
from bench.voice_bench import through_mic  # noqa: E402
from bench.voice_own import (  # noqa: E402
    EchoPath,
    _cancelled,
    _memory,
    agent_sentences,
    at_level,
    explanation_sentences,
    spoken,
    stream,
)
from bench.voice_walking import LEAD_S  # noqa: E402
from schemas.messages import Command  # noqa: E402
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice import synth  # noqa: E402
from services.voice.audio import SAMPLE_RATE, rounded_pcm  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.mic import CHUNK_S  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402
from voice46_look_back_probe import VOICES  # noqa: E402

RESIDUES = (-20.0, -30.0, -40.0)


class WebrtcAec:
    """WebRTC's AEC3 behind speexdsp's call (`cancel_echo(mic, ref)` on 10 ms frames)."""

    def __init__(self, filter_s: float) -> None:
        from livekit import rtc

        self._rtc = rtc
        self._apm = rtc.AudioProcessingModule(echo_cancellation=True)

    def cancel_echo(self, mic: list[int], ref: list[int]) -> list[int]:
        frame = len(mic)
        self._apm.process_reverse_stream(self._rtc.AudioFrame(np.asarray(ref, np.int16).tobytes(), SAMPLE_RATE, 1, frame))
        near = self._rtc.AudioFrame(np.asarray(mic, np.int16).tobytes(), SAMPLE_RATE, 1, frame)
        self._apm.process_stream(near)
        return np.frombuffer(bytes(near.data.cast("B")), "<i2").tolist()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--peaks", default="-12,-3")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--webrtc", action="store_true")
    args = ap.parse_args()
    if args.webrtc:
        echo._aec = WebrtcAec  # type: ignore[assignment]
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory() as tmp:
        voices = [spoken(s, tts, Path(tmp)) for s in agent_sentences() + explanation_sentences()]
    rng = np.random.default_rng(args.seed)
    stops = [synth.speak("stop", v, int(rng.integers(130, 190))) for v in VOICES * 2]
    engine, config, t0 = make_engine("spotter"), SegmenterConfig(), 1000.0
    ways = ("cold", "recalled") if args.webrtc else ("without", "cold", "recalled", *RESIDUES, "none left")
    for peak in (float(p) for p in args.peaks.split(",")):
        rng = np.random.default_rng(args.seed)
        heard: Counter[object] = Counter()
        for k, stop in enumerate(stops):
            path = EchoPath.draw(rng, (0.25, 0.6))
            voice = voices[k % len(voices)]
            scale = 10 ** (peak / 20) / (path.peak(voice) + 1e-12)
            memory = _memory([voices[(k + 1 + j) % len(voices)] for j in range(3)], path, scale, -70.0, 48000, rng, t0)
            echo_, late = path.echo(voice, rng)
            start = int(LEAD_S * SAMPLE_RATE)
            person = rng.normal(0.0, 10 ** (-70 / 20), start + echo_.size + SAMPLE_RATE)
            at = start + int(rng.uniform(0.2, max(0.3, voice.size / SAMPLE_RATE - 0.3)) * SAMPLE_RATE)
            said = at_level(stop, -26.0)
            person[at : at + said.size] += said
            robot = np.zeros_like(person)
            robot[start : start + echo_.size] = echo_ * scale
            x = through_mic(np.clip(person + robot, -1.0, 1.0), 48000)
            pcm, block = rounded_pcm(x), 2 * int(CHUNK_S * SAMPLE_RATE)
            played = [(t0 + start / SAMPLE_RATE + late, voice)]
            for way in ways:
                if way == "without":
                    z = x
                elif way in ("cold", "recalled"):
                    z = _cancelled(played, {}, pcm, block, t0, memory if way == "recalled" else None)
                else:
                    left = 0.0 if way == "none left" else 10 ** (float(way) / 20)
                    z = through_mic(np.clip(person + left * robot, -1.0, 1.0), 48000)
                heard[way] += any(cmd is Command.STOP and s < (at + said.size) / SAMPLE_RATE and e > at / SAMPLE_RATE
                                  for _, s, e, cmd, _ in stream(engine, z, config))
        print(f"{peak:+.0f} dBFS, of {len(stops)}: " + ", ".join(f"{w}: {heard[w]}" for w in ways), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
