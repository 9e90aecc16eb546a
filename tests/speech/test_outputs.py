"""Outputs on their own: a folder that cannot be written, a device that fails in the middle of a run."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

from schemas.messages import HealthStatus
from services.runtime import ServiceContext
from services.speech.config import OutputTarget, SpeechConfig
from services.speech.player import AplayOutput, FolderOutput, PlaybackError
from services.speech.queue import Utterance
from services.speech.service import SpeechService
from services.speech.tts import EspeakNg
from tests.conftest import wait_for
from tests.speech.conftest import StateLog


def test_unwritable_folder_is_reported(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("x")
    problem = FolderOutput(tmp_path / "file" / "speech").probe()
    assert problem is not None and "cannot write" in problem


def test_absent_sound_device_is_a_clear_playback_error(tmp_path: Path) -> None:
    out = AplayOutput("nosuchpcm")
    try:
        problem = out.probe()
        assert problem is not None and "device:nosuchpcm" in problem and "HRI_SPEECH_OUT" in problem
        audio = EspeakNg("en-us", 175, 100).synthesize("Yes.", out.path_for("x"))
        with pytest.raises(PlaybackError):
            out.play(audio, threading.Event())
        assert audio.path.exists()  # unplayed audio is kept for the folder fallback
    finally:
        out.close()
    assert not audio.path.exists()  # and its temporary folder goes with the output


def test_device_failing_mid_run_falls_back_to_the_folder(
    bus: ServiceContext, states: StateLog, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The device passed its probe, then went away: the utterance lands as a WAV; health degrades."""
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path))
    svc = SpeechService(bus, SpeechConfig(out=OutputTarget(device="nosuchpcm")))
    svc.check_engine()
    svc._output_error = None  # as if the probe had passed before the device vanished
    svc.speak(Utterance("mid", "Yes."))
    wait_for(lambda: states.ended("mid"), timeout=5)
    assert states.events() == [(True, "mid"), (False, "mid")]
    assert (tmp_path / "hri" / bus.robot / "speech" / "mid.wav").is_file()
    assert bus.status == HealthStatus.DEGRADED and svc.stats.spoken == 1
    svc.output.close()
