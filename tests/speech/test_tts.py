"""espeak-ng synthesis: real audio of plausible length, configurable voice, rate and volume, clear errors."""

from __future__ import annotations

import os
import subprocess
import sys
import wave
from pathlib import Path

import pytest

from services.speech.audio import wav_info
from services.speech.tts import EngineMissing, EspeakNg, SynthesisError, unknown_voice
from tests.conftest import ROOT

REFUSAL = "Sorry, I cannot do it."


def tts(voice: str = "en-us", rate: int = 160, volume: int = 100) -> EspeakNg:
    return EspeakNg(voice, rate, volume)


def test_refusal_is_speech_of_plausible_duration(tmp_path: Path) -> None:
    audio = tts().synthesize(REFUSAL, tmp_path / "r.wav")
    info = wav_info(audio.path)
    # Six words at 160 wpm: about 2 s; anything from 1 to 4 s is plausible, silence or a click is not.
    assert 1.0 < info.duration_s < 4.0
    assert audio.duration_s == pytest.approx(info.duration_s)
    assert info.sample_rate == 22050
    assert info.rms > 0.03
    assert info.active_fraction > 0.5
    assert list(tmp_path.iterdir()) == [tmp_path / "r.wav"]  # no partial file left behind


def test_silence_fails_the_speech_check(tmp_path: Path) -> None:
    """The speech check above can fail: a WAV of silence has no active windows."""
    path = tmp_path / "silence.wav"
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(22050)
        w.writeframes(b"\0\0" * 22050)
    info = wav_info(path)
    assert info.duration_s == pytest.approx(1.0)
    assert info.rms == 0.0 and info.active_fraction == 0.0


def test_rate_and_volume_change_the_audio(tmp_path: Path) -> None:
    slow = tts(rate=100).synthesize(REFUSAL, tmp_path / "slow.wav")
    fast = tts(rate=300).synthesize(REFUSAL, tmp_path / "fast.wav")
    assert slow.duration_s > 1.8 * fast.duration_s
    quiet = wav_info(tts(volume=40).synthesize(REFUSAL, tmp_path / "quiet.wav").path)
    loud = wav_info(tts(volume=160).synthesize(REFUSAL, tmp_path / "loud.wav").path)
    assert loud.rms > 2.5 * quiet.rms


def test_voice_changes_the_audio(tmp_path: Path) -> None:
    us = tts(voice="en-us").synthesize(REFUSAL, tmp_path / "us.wav").path.read_bytes()
    gb = tts(voice="en-gb").synthesize(REFUSAL, tmp_path / "gb.wav").path.read_bytes()
    assert us != gb


def test_unknown_voice_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(SynthesisError, match=r"voice.*espeak-ng --voices"):
        tts(voice="nosuchvoice").synthesize(REFUSAL, tmp_path / "x.wav")
    assert not any(tmp_path.iterdir())


def test_voice_names_are_checked_against_espeak_ngs_own_list() -> None:
    assert unknown_voice("en-us") is None and unknown_voice("en-US+f1") is None
    assert unknown_voice("gmw/en-GB-x-rp+klatt2") is None
    # espeak-ng falls back to its default voice without a word for an unknown variant
    assert "no variant 'nosuch'" in (unknown_voice("en-us+nosuch") or "")
    assert "no voice 'nosuchvoice'" in (unknown_voice("nosuchvoice") or "")
    assert unknown_voice("en-us", binary="no-such-espeak") is None  # reported as a missing engine


@pytest.mark.parametrize("command", [["say", "hello", "--out", "x.wav"], []])
def test_an_unknown_variant_is_refused_at_start(tmp_path: Path, command: list[str]) -> None:
    result = subprocess.run([sys.executable, "-m", "services.speech", *command], check=False, cwd=tmp_path,
                            env={**os.environ, "HRI_SPEECH_VOICE": "en-us+nosuch", "PYTHONPATH": str(ROOT)},
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "no variant 'nosuch'" in result.stderr and "--voices=variant" in result.stderr
    assert not (tmp_path / "x.wav").exists()


def test_text_that_looks_like_options_is_spoken_as_text(tmp_path: Path) -> None:
    audio = tts().synthesize("-v xx -w /etc/passwd --help", tmp_path / "opt.wav")
    assert wav_info(audio.path).duration_s > 1.0


def test_missing_binary_says_how_to_install(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    engine = tts()
    with pytest.raises(EngineMissing, match=r"espeak-ng.*not found.*apt-get install espeak-ng"):
        engine.check()
    with pytest.raises(EngineMissing, match="apt-get install espeak-ng"):
        engine.synthesize(REFUSAL, tmp_path / "x.wav")


def run_say(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "services.speech", "say", *args], check=False, cwd=ROOT,
                          env=env,
                          capture_output=True, text=True, timeout=60)


def test_say_writes_a_wav(tmp_path: Path) -> None:
    out = tmp_path / "reply.wav"
    result = run_say(REFUSAL, "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert '"duration_s"' in result.stdout
    assert wav_info(out).active_fraction > 0.5


def test_say_without_espeak_ng_exits_with_the_install_command(tmp_path: Path) -> None:
    result = run_say(REFUSAL, "--out", str(tmp_path / "x.wav"), env={"PATH": str(tmp_path)})
    assert result.returncode == 3
    assert "espeak-ng" in result.stderr and "apt-get install espeak-ng" in result.stderr
    assert not (tmp_path / "x.wav").exists()


def test_say_rejects_empty_text_and_bad_options(tmp_path: Path) -> None:
    empty = run_say("   ", "--out", str(tmp_path / "x.wav"))
    assert empty.returncode == 2 and "empty text" in empty.stderr
    bad_rate = run_say("hello", "--rate", "5000", "--out", str(tmp_path / "x.wav"))
    assert bad_rate.returncode == 2 and "--rate" in bad_rate.stderr
