"""Rounds voice37-37d: the live stream's VAD hears a quiet stream lifted (`SegmenterConfig.vad_lift_dbfs`; since 37d by a
second VAD, the default); the utterance's audio stays as it came."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.voice import synth
from services.voice.audio import from_pcm
from services.voice.level import Level
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig
from tests.voice.streams import emitted, word_stream
from tests.voice.test_level import at_peak

pytestmark = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")

OFF = replace(SegmenterConfig(), vad_lift_dbfs=None)
LIFT = replace(SegmenterConfig(), vad_lift_dbfs=-20.0, vad_lift_floor_dbfs=None, vad_lift_second=False,
               vad_lift_hold_s=0.0)  # one VAD hearing the lifted stream, as rounds voice37 and 37b


def test_the_lift_finds_words_too_quiet_for_the_vad_and_hands_them_over_unchanged() -> None:
    pcm = at_peak(word_stream("stop", "yes"), -46.0)
    assert emitted(pcm, OFF) == []
    found = [s for _, s in emitted(pcm, LIFT)]
    assert len(found) == 2
    for seg in found:  # the audio as it came: the lift is the VAD's alone
        start = int(seg.start_s * 16000) * 2
        assert seg.pcm == pcm[start : start + len(seg.pcm)]
        assert -48.0 < Level.of(seg.pcm).peak_dbfs < -44.0


def test_the_lift_falls_at_once_for_a_loud_frame_and_rises_only_when_it_has_left_the_window() -> None:
    config = replace(LIFT, vad_peak_s=0.3)  # 10 frames
    seg = Segmenter(config)

    def frame(peak: int) -> bytes:
        return np.full(480, peak, "<i2").tobytes()

    def db(gain: float) -> float:
        return round(20 * np.log10(gain), 1)

    assert db(seg._vad_gain(frame(33))) == 24.0  # a -60 dBFS hiss: the most it may lift
    assert db(seg._vad_gain(frame(206))) == 24.0  # a -44 dBFS frame: lifted to -20
    assert db(seg._vad_gain(frame(3277))) == 0.0  # -20 dBFS: no lift at once
    assert db(seg._vad_gain(frame(16384))) == 0.0  # never below 0 dB
    for _ in range(8):
        assert db(seg._vad_gain(frame(33))) == 0.0  # the loud frame is still within the window
    assert db(seg._vad_gain(frame(33))) == round(-20 - 20 * np.log10(3277 / 32768) + 0.0, 1) == 0.0
    assert db(seg._vad_gain(frame(33))) == 24.0  # all loud frames gone


def test_a_word_at_a_trained_level_is_cut_as_without_the_lift() -> None:
    """Speech at -14 dBFS: the same utterances, ending within a frame of where they end without the lift."""
    pcm = at_peak(word_stream("stop", "yes", "no"), -14.0)
    off = [s for _, s in emitted(pcm, OFF)]
    lift = [s for _, s in emitted(pcm, LIFT)]
    assert len(off) == len(lift) == 3
    for a, b in zip(off, lift, strict=True):
        assert abs(a.end_s - b.end_s) <= 0.03 + 1e-9  # a frame
        assert abs(a.start_s - b.start_s) <= 0.1  # the onset may be heard a little earlier
    assert np.abs(from_pcm(pcm)).max() > 0.19  # really at -14 dBFS


def test_vad_lift_setting() -> None:
    from services.voice.engine import EngineError
    from services.voice.service import VoiceSettings

    assert VoiceSettings(vad_lift="off").segmenter().vad_lift_dbfs is None
    assert VoiceSettings(vad_lift="-26").segmenter().vad_lift_dbfs == -26.0
    assert VoiceSettings().segmenter().vad_lift_dbfs == SegmenterConfig.vad_lift_dbfs  # the default
    for bad in ("5", "-41", "quiet", "nan"):
        with pytest.raises(EngineError, match="HRI_VOICE_VAD_LIFT"):
            VoiceSettings(vad_lift=bad).segmenter()


def test_a_bad_vad_lift_exits_2_naming_the_variable() -> None:
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    out = subprocess.run([sys.executable, "-m", "services.voice"], cwd=ROOT, capture_output=True, text=True,
                         check=False, timeout=60, env={**os.environ, "HRI_VOICE_VAD_LIFT": "loud", "HRI_VOICE_SOURCE": "stdin"})
    assert out.returncode == 2 and "HRI_VOICE_VAD_LIFT='loud'" in out.stderr


def test_the_floor_bound_keeps_a_noisy_stream_unlifted() -> None:
    """Round voice37b: with `vad_lift_floor_dbfs` the lift never brings the noise floor over that level."""
    frame = np.full(480, 206, "<i2").tobytes()  # -44 dBFS: round 37's lift would be 24 dB
    for floor_db, lift_db in ((-70.0, 15.0), (-40.0, 0.0)):
        seg = Segmenter(replace(LIFT, vad_lift_floor_dbfs=-55.0))
        seg._floor.append(10 ** (floor_db / 10))  # the noise floor, as mean square
        assert round(20 * np.log10(seg._vad_gain(frame)), 1) == lift_db


SECOND = replace(LIFT, vad_lift_second=True)


def at(start: float, end: float) -> Segment:
    """A segment over `start`..`end` (s), for `Segmenter._with_second`."""
    return Segment(b"", start, end)


def test_the_default_is_round_voice37ds_second_vad() -> None:
    config = SegmenterConfig()
    assert (config.vad_lift_dbfs, config.vad_lift_floor_dbfs, config.vad_lift_second, config.vad_lift_hold_s) == (
        -20.0, -55.0, True, 0.5)
    assert Segmenter()._second is not None and Segmenter(OFF)._second is None


@pytest.mark.parametrize("hold_s", [0.0, 0.5])
def test_a_second_vad_finds_the_quiet_words_and_leaves_the_loud_ones_to_the_first(hold_s: float) -> None:
    """Rounds voice37c and 37d: with `vad_lift_second` the first VAD hears the stream as it came and its utterances are
    cut exactly as without the lift; the second, lifted, adds only what the first did not hear at all."""
    config = replace(SECOND, vad_lift_hold_s=hold_s)
    quiet = at_peak(word_stream("stop", "yes"), -46.0)
    assert emitted(quiet, OFF) == []
    found = [s for _, s in emitted(quiet, config)]
    assert [(s.start_s, s.end_s) for s in found] == [(s.start_s, s.end_s) for _, s in emitted(quiet, LIFT)]
    assert len(found) == 2 and all(-48.0 < Level.of(s.pcm).peak_dbfs < -44.0 for s in found)
    loud = at_peak(word_stream("stop", "yes", "no"), -14.0)
    off = [(s.start_s, s.end_s, s.pcm) for _, s in emitted(loud, OFF)]
    assert len(off) == 3 and [(s.start_s, s.end_s, s.pcm) for _, s in emitted(loud, config)] == off


def test_an_utterance_of_the_second_vad_counts_only_where_the_first_heard_nothing() -> None:
    seg = Segmenter(SECOND)
    assert seg._second is not None and seg._peaks is None and seg._second._peaks is not None
    assert seg._second._second is None and seg._second.recognise is None  # one lifted VAD; it decodes nothing early

    mine = [at(1.0, 1.8)]
    both = seg._with_second(mine, [at(0.9, 2.0), at(3.0, 3.5)])
    assert [(s.start_s, s.end_s) for s in both] == [(1.0, 1.8), (3.0, 3.5)]  # the overlapping one is the first's
    assert seg._with_second([], [at(1.7, 2.4)]) == []  # overlaps an utterance the first heard before
    seg._speech = [b"\0\0"]  # the first is in an utterance now: the second's waits for nothing, it is dropped
    assert seg._with_second([], [at(5.0, 5.6)]) == []


def test_the_second_vads_utterance_is_held_back_and_dropped_if_the_first_starts_one_meanwhile() -> None:
    """Round voice37d: the lifted VAD may hear a loud word's faint onset alone and end before the first VAD starts on
    the word; held `vad_lift_hold_s`, that fragment is dropped, and a far word nobody else heard still counts."""
    seg = Segmenter(replace(SECOND, vad_lift_hold_s=0.5))

    def stream_time(seconds: float) -> None:
        seg._consumed = int(seconds * 16000) * 2

    stream_time(1.5)
    assert seg._with_second([], [at(1.0, 1.5)]) == []  # held until 2.0
    stream_time(1.8)
    seg._speech = [b"\0\0"]  # the first starts on the word
    assert seg._with_second([], []) == [] and seg._waiting == []  # the fragment is dropped
    seg._speech = []
    stream_time(4.0)
    assert seg._with_second([], [at(3.4, 4.0)]) == []
    stream_time(4.5)
    assert [(s.start_s, s.end_s) for s in seg._with_second([], [])] == [(3.4, 4.0)]  # nobody else heard it
    stream_time(6.0)
    assert seg._with_second([], [at(5.5, 6.0)]) == []
    assert [(s.start_s, s.end_s) for s in seg._with_second([], [], final=True)] == [(5.5, 6.0)]  # the stream ended
