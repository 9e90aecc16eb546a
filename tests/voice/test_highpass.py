"""A live stream's high-pass (`highpass.HighPass`, `SegmenterConfig.highpass_hz` and `highpass_from_dbfs`,
`HRI_VOICE_HIGHPASS`): a microphone's DC offset is taken out before the VAD once the stream shows one, a stream without
one is heard as it came, speech passes, and the filter's state runs on from chunk to chunk."""

from __future__ import annotations

import numpy as np
import pytest

from services.voice import synth
from services.voice.audio import SAMPLE_RATE, from_pcm, to_pcm
from services.voice.highpass import HighPass
from services.voice.level import Meter, verdict
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.vad import SileroEndpointer, SileroVad
from tests.voice.streams import emitted, word_stream
from tests.voice.test_level import at_peak

DC = 0.03
"""A microphone's offset, 0.03 of full scale (-30 dBFS): louder than speech peaking at -38 dBFS."""
ON = SegmenterConfig(highpass_hz=30.0)
"""`HRI_VOICE_HIGHPASS=30`, the default since round voice41e."""
OFF = SegmenterConfig(highpass_hz=None)
"""`HRI_VOICE_HIGHPASS=off`."""


def with_offset(pcm: bytes, offset: float = DC) -> bytes:
    return to_pcm(from_pcm(pcm) + offset)


def test_a_dc_offset_is_taken_out_and_a_voice_band_tone_passes() -> None:
    t = np.arange(SAMPLE_RATE) / SAMPLE_RATE
    x = DC + 0.1 * np.sin(2 * np.pi * 300 * t)
    y = from_pcm(HighPass(30.0)(to_pcm(x)))
    assert abs(float(from_pcm(to_pcm(x)).mean()) - DC) < 1e-3
    assert abs(float(y.mean())) < 3e-4  # from the first sample on: the filter starts settled on it
    assert 0.098 < float(np.abs(y[1600:]).max()) < 0.102  # 300 Hz within 0.2 dB
    assert 0.09 < float(np.abs(from_pcm(HighPass(30.0)(to_pcm(0.1 * np.sin(2 * np.pi * 100 * t))))[1600:]).max())


def test_chunks_of_any_size_give_the_stream_filtered_at_once() -> None:
    pcm = to_pcm(0.02 + 0.1 * np.random.default_rng(0).normal(size=8000))
    whole = HighPass(30.0)(pcm)
    hp, parts, at = HighPass(30.0), [], 0
    for n in (1, 2, 479, 960, 3, 1000, 0, 7):  # odd byte counts too: a sample split between two reads
        parts.append(hp(pcm[at : at + n]))
        at += n
    parts.append(hp(pcm[at:]))
    assert b"".join(parts) == whole
    assert len(whole) == len(pcm)


@pytest.mark.parametrize("hz", [0.0, -5.0, 8000.0])
def test_a_frequency_out_of_range_is_refused(hz: float) -> None:
    with pytest.raises(ValueError, match="high-pass"):
        HighPass(hz)


def test_the_meter_does_not_take_an_offset_for_noise() -> None:
    quiet, offset = Meter(), Meter()
    hiss = to_pcm(np.random.default_rng(3).normal(0.0, 3e-4, 960))
    quiet.feed(hiss)
    offset.feed(with_offset(hiss))
    assert abs(quiet.detail()["input_floor_dbfs"] - offset.detail()["input_floor_dbfs"]) < 0.5  # type: ignore[operator]


def test_highpass_setting() -> None:
    from services.voice.engine import EngineError
    from services.voice.service import VoiceSettings

    assert VoiceSettings().segmenter().highpass_hz == SegmenterConfig.highpass_hz == 30.0
    assert VoiceSettings(highpass="off").segmenter().highpass_hz is None
    assert VoiceSettings(highpass="30").segmenter().highpass_hz == 30.0
    assert VoiceSettings(highpass="60").segmenter().highpass_hz == 60.0
    for bad in ("0", "400", "dc", "nan"):
        with pytest.raises(EngineError, match="HRI_VOICE_HIGHPASS"):
            VoiceSettings(highpass=bad).segmenter()


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_speech_over_an_offset_is_cut_and_measured_as_without_it() -> None:
    """Without the high-pass the segmenter takes the offset for the room's noise: every utterance's speech-to-noise
    estimate falls to about 0 dB (so none counts as clear, and the health check calls each one noisy)."""
    pcm = at_peak(word_stream("stop", "yes"), -38.0)
    clean = [s for _, s in emitted(pcm, ON)]
    offset = [s for _, s in emitted(with_offset(pcm), ON)]
    assert len(clean) == len(offset) == 2
    for a, b in zip(clean, offset, strict=True):
        assert abs(a.start_s - b.start_s) <= 0.031 and abs(a.end_s - b.end_s) <= 0.031  # a frame: the
        # levels and the VADs start anew at the switch
        assert a.snr_db is not None and b.snr_db is not None and abs(a.snr_db - b.snr_db) < 1.0 and a.snr_db > 10
        assert abs(float(from_pcm(b.pcm).mean())) < 1e-3  # the utterance comes without the offset
    raw = [s for _, s in emitted(with_offset(pcm), OFF)]
    assert raw and all(s.snr_db is not None and s.snr_db < 3 for s in raw)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
@pytest.mark.parametrize("peak", [-44.0, -3.0])
def test_a_stream_without_an_offset_is_heard_exactly_as_without_the_high_pass(peak: float) -> None:
    pcm = at_peak(word_stream("stop", "yes", "no"), peak)
    on = [(t, s.pcm, s.start_s, s.end_s, s.snr_db) for t, s in emitted(pcm, ON)]
    off = [(t, s.pcm, s.start_s, s.end_s, s.snr_db) for t, s in emitted(pcm, OFF)]
    assert on and on == off


def test_the_high_pass_is_switched_on_by_an_offset_and_not_by_a_walking_robot() -> None:
    from bench.ego_noise import EgoNoiseModel, ego_noise

    def switched(x: np.ndarray) -> bool:
        seg, pcm = Segmenter(ON), to_pcm(x)
        for k in range(0, len(pcm), 960):
            seg.feed(pcm[k : k + 960])
        return seg.highpass_on

    hiss = np.random.default_rng(5).normal(0.0, 3e-4, 2 * SAMPLE_RATE)
    assert not switched(hiss)
    assert switched(hiss + 0.005)  # -46 dBFS
    assert not switched(hiss + 0.002)  # -54 dBFS: under `highpass_from_dbfs`
    assert not switched(0.1 * ego_noise(6.0, np.random.default_rng(1), EgoNoiseModel()))  # -20 dBFS RMS of servos


def test_a_knock_is_not_an_offset() -> None:
    """Round voice43: a short loud push one way (a knock on the robot, a microphone's pop, a recording that starts or
    ends mid-sound) leaves the last second's mean as far from zero as an offset would, with far more power around it;
    the switch asks that the mean carry `highpass_dc_share` of the power, as a steady offset does."""
    rng = np.random.default_rng(5)
    n = SAMPLE_RATE // 20
    knock = 0.2 * np.sin(np.pi * np.arange(n) / n)  # 50 ms
    x = np.concatenate([rng.normal(0.0, 3e-4, SAMPLE_RATE), knock, rng.normal(0.0, 3e-4, SAMPLE_RATE)])

    def switched(config: SegmenterConfig) -> bool:
        seg, pcm = Segmenter(config), to_pcm(x)
        for k in range(0, len(pcm), 960):
            seg.feed(pcm[k : k + 960])
        return seg.highpass_on

    assert switched(SegmenterConfig(highpass_dc_share=0.0))  # the mean alone: the rule before round voice43
    assert not switched(ON)


def test_both_vads_start_again_when_the_high_pass_switches_on() -> None:
    """Round voice41c: Silero's state after half a second of an offset made it find more words, far words and other
    words alike, for a second or more. At the switch both VADs forget what they heard: from there they judge the
    stream as a VAD that never heard the offset would."""
    rng = np.random.default_rng(7)
    seg, pcm = Segmenter(ON), to_pcm(rng.normal(0.0, 3e-4, SAMPLE_RATE) + DC)
    k = 0
    while not seg.highpass_on:
        seg.feed(pcm[k : k + 960])
        k += 960
    assert seg._second is not None and 0.4 < k / 2 / SAMPLE_RATE < 0.6
    switched = HighPass(30.0)(pcm[k - 960 : k])  # the chunk that switched it on: one frame, heard after forgetting
    frames = [to_pcm(0.05 * np.sin(2 * np.pi * f * np.arange(480) / SAMPLE_RATE)) for f in (200, 300, 400, 500)]
    for ep in (seg._ep, seg._second._ep):
        assert isinstance(ep, SileroEndpointer)
        fresh = SileroVad()
        fresh(switched, ep.gain)
        assert [ep._vad(f) for f in frames] == [fresh(f) for f in frames]
    heard = SileroVad()
    for frame in [pcm[:960]] * 16 + [switched]:
        heard(frame)
    fresh = SileroVad()
    fresh(switched)
    assert [heard(f) for f in frames] != [fresh(f) for f in frames]  # the state it would otherwise have kept


def test_a_vad_forgets_only_outside_speech() -> None:
    ep = SileroEndpointer()
    ep.in_speech = True
    with pytest.raises(RuntimeError, match="outside speech"):
        ep.forget()


def test_the_level_check_says_when_a_microphone_needs_the_high_pass() -> None:
    hiss = to_pcm(np.random.default_rng(4).normal(0.0, 3e-4, 960))
    clean, offset = Meter(), Meter()
    for _ in range(20):
        clean.feed(hiss)
        offset.feed(with_offset(hiss, 0.005))  # -46 dBFS
    assert round(float(offset.detail()["input_offset_dbfs"])) == -46  # type: ignore[arg-type]
    assert "HRI_VOICE_HIGHPASS=30" in verdict(offset, [])
    assert "HRI_VOICE_HIGHPASS" not in verdict(offset, [], highpass=True)  # already taking it out
    assert "HRI_VOICE_HIGHPASS" not in verdict(clean, [])


def test_the_level_check_says_when_the_high_pass_switches_on() -> None:
    """`python -m services.voice level` (the high-pass on by default) says when a stream's offset switches it on, as
    the service's log does, and names no variable to set; with `--highpass off` it asks for one instead."""
    import subprocess
    import sys

    from tests.conftest import ROOT

    pcm = with_offset(to_pcm(np.random.default_rng(6).normal(0.0, 3e-4, 2 * SAMPLE_RATE)))

    def check(*args: str) -> str:
        return subprocess.run([sys.executable, "-m", "services.voice", "level", "--source", "stdin", *args], cwd=ROOT,
                              input=pcm, capture_output=True, check=True, timeout=60).stdout.decode()

    out = check()
    assert "(high-pass switched on: a DC offset of -30." in out and "HRI_VOICE_HIGHPASS" not in out
    out = check("--highpass", "off")
    assert "high-pass switched on" not in out and "HRI_VOICE_HIGHPASS=30" in out


def test_the_stream_path_says_when_the_high_pass_switches_on() -> None:
    """`sources.stream_utterances` tells the service the high-pass's state as a stream starts and when an offset
    switches it on (the service's log and health, `highpass_on`), with the offset that did."""
    from services.voice.sources import stream_utterances

    hiss = to_pcm(np.random.default_rng(3).normal(0.0, 3e-4, 2 * SAMPLE_RATE))
    for pcm, told in ((hiss, [(False, 0.0)]), (with_offset(hiss), [(False, 0.0), (True, pytest.approx(DC, rel=0.02))])):
        states: list[tuple[bool, float]] = []
        list(stream_utterances((pcm[k : k + 960] for k in range(0, len(pcm), 960)), "stream", ON,
                               on_highpass=lambda on, offset, states=states: states.append((on, offset))))
        assert states == told
