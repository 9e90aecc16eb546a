"""The live stream's VAD in noise that never stops: a walking robot's own servos and footfalls
(`bench/ego_noise.py`), where WebRTC's VAD never ends an utterance and Silero's does."""

from __future__ import annotations

import numpy as np
import pytest

from bench.ego_noise import EgoNoiseModel, ego_noise, joint_speeds, mix
from schemas.messages import Command
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig
from services.voice.vad import FRAME_SAMPLES, SileroEndpointer, silero_model_path

LEAD_S = 1.5


def _segments(pcm: bytes, vad: str) -> list[Segment]:
    seg = Segmenter(SegmenterConfig(vad=vad))
    step = 4800  # 150 ms chunks, not a multiple of the VAD frame
    return [s for i in range(0, len(pcm), step) for s in seg.feed(pcm[i : i + step])] + seg.flush()


def _word_in_walking_noise(word: str, snr_db: float, seed: int = 3) -> tuple[bytes, float, float]:
    """The stream, and where the word's speech starts and ends in it (s)."""
    speech = np.frombuffer(read_wav(synth.speech_clip(word, "en-us", 150).path), "<i2") / 32768.0
    seconds = LEAD_S + speech.size / SAMPLE_RATE + 1.5
    x = mix(speech, ego_noise(seconds, np.random.default_rng(seed)), snr_db, int(LEAD_S * SAMPLE_RATE))
    return to_pcm(np.clip(x, -1, 1)), LEAD_S + synth.PAD_S, LEAD_S + speech.size / SAMPLE_RATE - synth.PAD_S


def test_ego_noise_is_unit_rms_reproducible_and_follows_the_gait() -> None:
    a = ego_noise(2.0, np.random.default_rng(1))
    b = ego_noise(2.0, np.random.default_rng(1))
    assert a.shape == (2 * SAMPLE_RATE,) and np.array_equal(a, b)
    assert np.sqrt(np.mean(a**2)) == pytest.approx(1.0)
    speeds, landings = joint_speeds(3.0)
    assert speeds.shape[1] == 18 and speeds.max() > 100.0  # deg/s: the legs and arms move
    assert np.allclose(np.diff(landings), 0.3, atol=0.02)  # a foot lands every half period
    standing = ego_noise(2.0, np.random.default_rng(1), EgoNoiseModel(walking=False))
    # walking, the loudness swings with every step; standing, it is steady
    def swing(x: np.ndarray) -> float:
        env = np.sqrt(np.mean(x[: x.size // 800 * 800].reshape(-1, 800) ** 2, axis=1))
        return float(env.std() / env.mean())

    assert swing(a) > 2 * swing(standing)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_silero_ends_a_word_in_walking_noise_where_webrtc_does_not() -> None:
    pcm, start, end = _word_in_walking_noise("stop", 15.0)
    webrtc = _segments(pcm, "webrtc")
    assert max(s.end_s - s.start_s for s in webrtc) > 3.0  # the stream is "speech" from start to end
    silero = _segments(pcm, "silero")
    over = [s for s in silero if s.start_s < end and s.end_s > start]
    assert len(over) == 1
    assert over[0].end_s - over[0].start_s < 1.2
    assert over[0].start_s <= start + 0.1 and over[0].end_s >= end - 0.3


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_stop_is_heard_in_walking_noise_through_the_stream() -> None:
    from services.voice.engine_spotter import SpotterEngine

    spotter = SpotterEngine.from_path()
    pcm, _, _ = _word_in_walking_noise("stop", 20.0)
    heard = [spotter.recognise(s.pcm) for s in _segments(pcm, "silero")]
    assert [r.command for r in heard if r.command is not None] == [Command.STOP]


def test_walking_noise_alone_is_not_speech() -> None:
    pcm = to_pcm(0.03 * ego_noise(8.0, np.random.default_rng(4)))
    assert _segments(pcm, "silero") == []


def test_silero_endpointer_frames_and_errors() -> None:
    ep = SileroEndpointer()
    assert ep.frame_bytes == FRAME_SAMPLES * 2
    with pytest.raises(ValueError, match="frames of 960 bytes"):
        ep.process(b"\0" * 100)
    assert ep.process(b"\0" * ep.frame_bytes) is None and not ep.in_speech
    assert ep.end_stream(b"") is None
    assert silero_model_path().name == "silero_vad.onnx"


def test_silero_end_threshold_defaults_to_silero_rule_and_may_not_exceed_the_start() -> None:
    assert SileroEndpointer(threshold=0.5).neg_threshold == pytest.approx(0.35)
    assert SileroEndpointer(threshold=0.4, end_threshold=0.35).neg_threshold == 0.35
    with pytest.raises(ValueError, match="end threshold 0.45 is above the start threshold 0.4"):
        SileroEndpointer(threshold=0.4, end_threshold=0.45)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_lower_start_threshold_starts_no_later_and_ends_where_the_end_threshold_says() -> None:
    pcm, start, end = _word_in_walking_noise("stop", 15.0)
    step = 960

    def over(config: SegmenterConfig) -> list[Segment]:
        seg = Segmenter(config)
        segs = [s for i in range(0, len(pcm), step) for s in seg.feed(pcm[i : i + step])] + seg.flush()
        return [s for s in segs if s.start_s < end and s.end_s > start]

    (high,) = over(SegmenterConfig(threshold=0.5, end_threshold=0.35))
    (low,) = over(SegmenterConfig(threshold=0.4, end_threshold=0.35))
    assert low.start_s <= high.start_s and abs(low.end_s - high.end_s) < 0.1


def test_unknown_vad_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown VAD 'energy'"):
        Segmenter(SegmenterConfig(vad="energy"))


def test_unknown_vad_setting_exits_2_naming_the_variable() -> None:
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    out = subprocess.run([sys.executable, "-m", "services.voice"], cwd=ROOT, capture_output=True, text=True,
                         check=False, timeout=60,
                         env={**os.environ, "HRI_VOICE_VAD": "energy", "HRI_VOICE_SOURCE": "stdin"})
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "HRI_VOICE_VAD='energy'" in out.stderr and "silero" in out.stderr


def test_walking_bench_plays_a_users_recording_at_unit_rms() -> None:
    from bench.voice_walking import noise_source

    recording = np.sin(np.arange(8000) / 10.0)  # shorter than asked: repeated
    x = noise_source(1.5, np.random.default_rng(0), recording)
    assert x.size == int(1.5 * SAMPLE_RATE)
    assert np.sqrt(np.mean(x**2)) == pytest.approx(1.0)
