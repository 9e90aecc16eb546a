"""Round voice37: the live stream's VAD hears a quiet stream lifted (`SegmenterConfig.vad_lift_dbfs`); the utterance's
audio stays as it came."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.voice import synth
from services.voice.audio import from_pcm
from services.voice.level import Level
from services.voice.segmenter import Segmenter, SegmenterConfig
from tests.voice.streams import emitted, word_stream
from tests.voice.test_level import at_peak

pytestmark = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")

OFF = replace(SegmenterConfig(), vad_lift_dbfs=None)
LIFT = replace(SegmenterConfig(), vad_lift_dbfs=-20.0)


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
