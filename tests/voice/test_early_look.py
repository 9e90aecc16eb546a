"""The segmenter's early look: after `early_quiet_s` of quiet the utterance so far is decoded, and ends there only
if the engine accepts a command confidently enough; otherwise the segmenter waits for the whole end window."""

from __future__ import annotations

import pytest

from schemas.messages import Command
from services.voice import synth
from services.voice.engine import EngineError
from services.voice.segmenter import SegmenterConfig
from services.voice.service import VoiceSettings
from tests.voice.streams import Judge, emitted, word_stream

# The early look alone, with the VAD thresholds it was judged with (rounds 16, 16b: Silero's 0.5 / 0.35); with
# round 18's start (0.4) the onset moves a frame and the spotter is no longer sure of this "stop" at the look.
ON = SegmenterConfig(early_quiet_s=0.09, clear_quiet_s=None, threshold=0.5, end_threshold=0.35)


needs_espeak = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")


@needs_espeak
def test_a_sure_command_ends_the_utterance_at_the_early_look() -> None:
    pcm = word_stream("stop")
    whole = emitted(pcm, ON, None)
    early = emitted(pcm, ON, Judge(Command.STOP))
    assert len(whole) == len(early) == 1 and whole[0][1].recognition is None
    (t_whole, s_whole), (t_early, s_early) = whole[0], early[0]
    assert t_whole - t_early == pytest.approx(0.06, abs=1e-6)  # 2 of the end window's 5 frames sooner
    assert s_early.recognition is not None and s_early.recognition.command == Command.STOP
    assert s_early.start_s == s_whole.start_s and s_early.end_s < s_whole.end_s


@needs_espeak
@pytest.mark.parametrize("judge", [Judge(None), Judge(Command.STOP, confidence=0.8)])
def test_an_unsure_look_waits_for_the_whole_end_window(judge: Judge) -> None:
    pcm = word_stream("stop")
    whole = emitted(pcm, ON, None)
    looked = emitted(pcm, SegmenterConfig(early_quiet_s=0.09, early_confidence=0.85, clear_quiet_s=None, threshold=0.5,
                                                end_threshold=0.35), judge)
    assert judge.calls >= 1
    assert [(t, s.pcm, s.recognition) for t, s in looked] == [(t, s.pcm, None) for t, s in whole]


@needs_espeak
def test_after_an_early_end_the_next_word_is_its_own_utterance() -> None:
    pcm = word_stream("stop", "go", gap_s=0.12)  # 120 ms apart: one utterance for the 150 ms end window
    whole = emitted(pcm, ON, None)
    early = emitted(pcm, ON, Judge(Command.STOP))
    assert len(whole) == 1
    assert len(early) == 2 and all(s.recognition is not None for _, s in early)
    assert early[0][1].end_s <= early[1][1].start_s + SegmenterConfig.pre_roll_s


@needs_espeak
def test_the_early_look_is_off_with_webrtc_and_by_default() -> None:
    pcm = word_stream("stop")
    for config in (SegmenterConfig(vad="webrtc", early_quiet_s=0.09), SegmenterConfig(clear_quiet_s=None)):
        judge = Judge(Command.STOP)
        assert all(s.recognition is None for _, s in emitted(pcm, config, judge)) and judge.calls == 0


@needs_espeak
def test_the_spotter_hears_the_same_command_sooner_through_the_early_look() -> None:
    from services.voice.engine_spotter import SpotterEngine

    spotter = SpotterEngine.from_path()
    pcm = word_stream("no", "stop")
    whole = [(t, spotter.recognise(s.pcm).command) for t, s in emitted(pcm, ON, None)]
    early = [(t, s.recognition.command if s.recognition else spotter.recognise(s.pcm).command)
             for t, s in emitted(pcm, ON, spotter.recognise)]
    assert [c for _, c in whole] == [c for _, c in early] == [Command.NO, Command.STOP]
    assert all(te < tw for (te, _), (tw, _) in zip(early, whole, strict=True))


def test_early_look_setting() -> None:
    assert VoiceSettings().segmenter().early_quiet_s == SegmenterConfig.early_quiet_s
    assert VoiceSettings(early_look="0.09").segmenter().early_quiet_s == 0.09
    assert VoiceSettings(early_look="off").segmenter().early_quiet_s is None
    assert VoiceSettings(early_look="0.06").segmenter().early_quiet_s == 0.06
    for bad in ("0.15", "0", "soon"):
        with pytest.raises(EngineError, match="HRI_VOICE_EARLY_LOOK"):
            VoiceSettings(early_look=bad).segmenter()


@pytest.mark.parametrize(("variable", "value"), [("HRI_VOICE_EARLY_LOOK", "soon"), ("HRI_VOICE_CLEAR_WINDOW", "short")])
def test_a_bad_stream_window_setting_exits_2_naming_the_variable(variable: str, value: str) -> None:
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    out = subprocess.run([sys.executable, "-m", "services.voice"], cwd=ROOT, capture_output=True, text=True,
                         check=False, timeout=60, env={**os.environ, variable: value, "HRI_VOICE_SOURCE": "stdin"})
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and f"{variable}={value!r}" in out.stderr
