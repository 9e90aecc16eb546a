"""The segmenter's early look: after `early_quiet_s` of quiet the utterance so far is decoded, and ends there only
if the engine accepts a command confidently enough; otherwise the segmenter waits for the whole end window."""

from __future__ import annotations

import numpy as np
import pytest

from schemas.messages import Command
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.engine import EngineError, Recognition
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig
from services.voice.service import VoiceSettings

LEAD_S = 1.0
ON = SegmenterConfig(early_quiet_s=0.09)
STEP = 960  # 30 ms chunks, as the service's sources


def _stream(*words: str, gap_s: float = 0.8) -> bytes:
    """The words (espeak-ng en-us) one after another in a faint hiss, `gap_s` from one word's end to the next."""
    parts = [np.zeros(int(LEAD_S * SAMPLE_RATE))]
    for word in words:
        speech = np.frombuffer(read_wav(synth.speech_clip(word, "en-us", 150).path), "<i2") / 32768.0
        loud = np.flatnonzero(np.abs(speech) > 0.02 * np.abs(speech).max())  # without the silence around it
        parts += [speech[loud[0] : loud[-1] + 1], np.zeros(int(gap_s * SAMPLE_RATE))]
    x = np.concatenate([*parts, np.zeros(SAMPLE_RATE)])
    return to_pcm(x + np.random.default_rng(1).normal(0, 3e-4, x.size))


class _Judge:
    """A recogniser that records what it was asked and answers as told."""

    def __init__(self, command: Command | None, confidence: float = 0.9) -> None:
        self.command, self.confidence, self.calls = command, confidence, 0

    def __call__(self, pcm: bytes) -> Recognition:
        self.calls += 1
        return Recognition(self.command, self.command.value if self.command else "other", self.confidence, "test")


def _emitted(pcm: bytes, config: SegmenterConfig, judge: _Judge | None) -> list[tuple[float, Segment]]:
    """(stream time at which the segment was emitted, the segment)."""
    seg = Segmenter(config, recognise=judge)
    out = []
    for k in range(0, len(pcm), STEP):
        out += [((k + STEP) / 2 / SAMPLE_RATE, s) for s in seg.feed(pcm[k : k + STEP])]
    return out


needs_espeak = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")


@needs_espeak
def test_a_sure_command_ends_the_utterance_at_the_early_look() -> None:
    pcm = _stream("stop")
    whole = _emitted(pcm, ON, None)
    early = _emitted(pcm, ON, _Judge(Command.STOP))
    assert len(whole) == len(early) == 1 and whole[0][1].recognition is None
    (t_whole, s_whole), (t_early, s_early) = whole[0], early[0]
    assert t_whole - t_early == pytest.approx(0.06, abs=1e-6)  # 2 of the end window's 5 frames sooner
    assert s_early.recognition is not None and s_early.recognition.command == Command.STOP
    assert s_early.start_s == s_whole.start_s and s_early.end_s < s_whole.end_s


@needs_espeak
@pytest.mark.parametrize("judge", [_Judge(None), _Judge(Command.STOP, confidence=0.8)])
def test_an_unsure_look_waits_for_the_whole_end_window(judge: _Judge) -> None:
    pcm = _stream("stop")
    whole = _emitted(pcm, ON, None)
    looked = _emitted(pcm, SegmenterConfig(early_quiet_s=0.09, early_confidence=0.85), judge)
    assert judge.calls >= 1
    assert [(t, s.pcm, s.recognition) for t, s in looked] == [(t, s.pcm, None) for t, s in whole]


@needs_espeak
def test_after_an_early_end_the_next_word_is_its_own_utterance() -> None:
    pcm = _stream("stop", "go", gap_s=0.12)  # 120 ms apart: one utterance for the 150 ms end window
    whole = _emitted(pcm, ON, None)
    early = _emitted(pcm, ON, _Judge(Command.STOP))
    assert len(whole) == 1
    assert len(early) == 2 and all(s.recognition is not None for _, s in early)
    assert early[0][1].end_s <= early[1][1].start_s + SegmenterConfig.pre_roll_s


@needs_espeak
def test_the_early_look_is_off_with_webrtc_and_by_default() -> None:
    pcm = _stream("stop")
    for config in (SegmenterConfig(vad="webrtc", early_quiet_s=0.09), SegmenterConfig()):
        judge = _Judge(Command.STOP)
        assert all(s.recognition is None for _, s in _emitted(pcm, config, judge)) and judge.calls == 0


@needs_espeak
def test_the_spotter_hears_the_same_command_sooner_through_the_early_look() -> None:
    from services.voice.engine_spotter import SpotterEngine

    spotter = SpotterEngine.from_path()
    pcm = _stream("no", "stop")
    whole = [(t, spotter.recognise(s.pcm).command) for t, s in _emitted(pcm, ON, None)]
    early = [(t, s.recognition.command if s.recognition else spotter.recognise(s.pcm).command)
             for t, s in _emitted(pcm, ON, spotter.recognise)]
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


def test_a_bad_early_look_setting_exits_2_naming_the_variable() -> None:
    import os
    import subprocess
    import sys

    from tests.conftest import ROOT

    out = subprocess.run([sys.executable, "-m", "services.voice"], cwd=ROOT, capture_output=True, text=True,
                         check=False, timeout=60,
                         env={**os.environ, "HRI_VOICE_EARLY_LOOK": "soon", "HRI_VOICE_SOURCE": "stdin"})
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "HRI_VOICE_EARLY_LOOK='soon'" in out.stderr
