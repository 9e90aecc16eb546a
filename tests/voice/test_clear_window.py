"""The clear window: in a clear stream (speech at least `clear_snr_db` over the noise floor) an utterance ends
after `clear_quiet_s` of quiet; in noise it waits for the whole end window (`quiet_s`), as without it."""

from __future__ import annotations

import pytest

from services.voice import synth
from services.voice.engine import EngineError
from services.voice.segmenter import SegmenterConfig
from services.voice.service import VoiceSettings
from tests.voice.streams import emitted, word_stream

WHOLE = SegmenterConfig(clear_quiet_s=None)
CLEAR = SegmenterConfig(clear_quiet_s=0.09, clear_snr_db=30.0)
needs_espeak = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")


@needs_espeak
def test_in_a_clear_stream_a_word_ends_after_the_short_window() -> None:
    pcm = word_stream("stop", "yes")
    whole, clear = emitted(pcm, WHOLE), emitted(pcm, CLEAR)
    assert len(whole) == len(clear) == 2
    for (t_whole, s_whole), (t_clear, s_clear) in zip(whole, clear, strict=True):
        assert t_whole - t_clear == pytest.approx(0.06, abs=1e-6)  # 2 of the end window's 5 frames sooner
        assert s_clear.start_s == s_whole.start_s and s_clear.end_s < s_whole.end_s
        assert s_clear.snr_db is not None and s_clear.snr_db >= 30.0


@needs_espeak
def test_in_noise_the_whole_end_window_is_kept() -> None:
    pcm = word_stream("stop", "yes", noise_db=15.0)
    whole, clear = emitted(pcm, WHOLE), emitted(pcm, CLEAR)
    assert whole and [(t, s.pcm) for t, s in clear] == [(t, s.pcm) for t, s in whole]
    assert all(s.snr_db is not None and s.snr_db < 30.0 for _, s in clear)


@needs_espeak
def test_the_threshold_decides() -> None:
    pcm = word_stream("stop", noise_db=15.0)
    loose = emitted(pcm, SegmenterConfig(clear_quiet_s=0.09, clear_snr_db=5.0))
    whole = emitted(pcm, WHOLE)
    assert len(loose) == len(whole) == 1 and loose[0][0] < whole[0][0]


@needs_espeak
def test_webrtc_has_no_clear_window_and_no_estimate() -> None:
    pcm = word_stream("stop")
    with_it = emitted(pcm, SegmenterConfig(vad="webrtc", clear_quiet_s=0.09))
    without = emitted(pcm, SegmenterConfig(vad="webrtc", clear_quiet_s=None))
    assert [(t, s.pcm) for t, s in with_it] == [(t, s.pcm) for t, s in without]
    assert all(s.snr_db is None for _, s in with_it)


def test_clear_window_setting() -> None:
    assert VoiceSettings().segmenter().clear_quiet_s == SegmenterConfig.clear_quiet_s
    assert VoiceSettings(clear_window="0.09").segmenter().clear_quiet_s == 0.09
    assert VoiceSettings(clear_window="off").segmenter().clear_quiet_s is None
    for bad in ("0.15", "-1", "short"):
        with pytest.raises(EngineError, match="HRI_VOICE_CLEAR_WINDOW"):
            VoiceSettings(clear_window=bad).segmenter()
    # at start, a bad value exits 2 naming the variable: test_early_look.py, with the early look's
