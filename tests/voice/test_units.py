"""Lexicon, policy, audio checks, source parsing and the spool watcher (no speech engine needed)."""

from __future__ import annotations

import os
import time
import wave
from pathlib import Path

import numpy as np
import pytest

from schemas.messages import Command
from services.voice.audio import AudioError, from_pcm, read_wav, rounded_pcm, to_pcm, write_wav
from services.voice.engine_pocketsphinx import calibrate
from services.voice.lexicon import Lexicon, LexiconError
from services.voice.policy import Policy, Word, default_thresholds
from services.voice.sources import SourceError, SourceSpec, SpoolWatcher


def tone(seconds: float = 0.5) -> bytes:
    t = np.arange(int(16000 * seconds)) / 16000
    return to_pcm(0.3 * np.sin(2 * np.pi * 440 * t))


def test_lexicon_maps_words_and_synonyms() -> None:
    lex = Lexicon()
    assert lex.lookup("STOP") == Command.STOP
    assert lex.lookup("sit") == Command.DOWN
    assert lex.lookup("table") is None
    assert lex.commands_in(["please", "halt"]) == [Command.STOP]


def test_lexicon_file_errors_are_clear(tmp_path: Path) -> None:
    bad = tmp_path / "lex.yaml"
    bad.write_text("fly: [fly]\n")
    with pytest.raises(LexiconError, match="unknown command 'fly'"):
        Lexicon.load(bad)
    clash = tmp_path / "clash.yaml"
    clash.write_text("go: [walk]\nstop: [walk]\n")
    with pytest.raises(LexiconError, match="maps to both"):
        Lexicon.load(clash)
    good = tmp_path / "good.json"
    good.write_text('{"go": ["walk"], "stop": "halt"}')
    assert Lexicon.load(good).lookup("walk") == Command.GO


def test_policy_is_cautious_about_go() -> None:
    policy = Policy(default_thresholds(go=0.9, other=0.5))
    lex = Lexicon()
    assert policy.decide([Word("go", 0.95)], lex).command == Command.GO
    assert policy.decide([Word("go", 0.8)], lex).command is None  # below go's threshold
    assert policy.decide([Word("please", 0.9), Word("go", 0.99)], lex).command is None  # go must be alone
    assert policy.decide([Word("please", 0.9), Word("stop", 0.6)], lex).command == Command.STOP
    assert policy.decide([Word("stop", 0.9), Word("go", 0.99)], lex).command is None  # two commands
    assert policy.decide([Word("table", 0.99)], lex).command is None


def test_calibration_puts_accepted_commands_at_or_above_half() -> None:
    assert calibrate(0.6, 0.6) == pytest.approx(0.5)
    assert calibrate(1.0, 0.3) == pytest.approx(1.0)
    assert calibrate(0.2, 0.4) < 0.5


def test_bad_wav_files_give_clear_errors(tmp_path: Path) -> None:
    not_audio = tmp_path / "notes.wav"
    not_audio.write_text("this is not audio")
    with pytest.raises(AudioError, match="not a PCM WAV"):
        read_wav(not_audio)
    wrong_rate = tmp_path / "cd.wav"
    with wave.open(str(wrong_rate), "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(2)
        w.setframerate(44100)
        w.writeframes(b"\0" * 4000)
    with pytest.raises(AudioError, match="44100 Hz.*need 16000 Hz"):
        read_wav(wrong_rate)
    with pytest.raises(AudioError, match="no such file"):
        read_wav(tmp_path / "missing.wav")


def test_source_specs(tmp_path: Path) -> None:
    assert SourceSpec.parse("mic") == SourceSpec("mic")
    assert SourceSpec.parse("mic:2") == SourceSpec("mic", "2")
    assert SourceSpec.parse("stdin").kind == "stdin"
    assert SourceSpec.parse(f"watch:{tmp_path}") == SourceSpec("watch", str(tmp_path))
    assert SourceSpec.parse(str(tmp_path)).kind == "folder"
    assert SourceSpec.parse(str(tmp_path / "a.wav")).kind == "file"
    with pytest.raises(SourceError, match="watch:<dir>"):
        SourceSpec.parse(str(tmp_path / "nothing-here"))


def test_spool_watcher_skips_tmp_and_waits_for_complete_files(tmp_path: Path) -> None:
    watcher = SpoolWatcher(tmp_path, settle_s=0.2)
    write_wav(tmp_path / "a.wav.tmp", tone())
    assert watcher.ready() == []
    (tmp_path / "a.wav.tmp").replace(tmp_path / "a.wav")
    assert [p.name for p in watcher.ready()] == ["a.wav"]
    watcher.done(tmp_path / "a.wav")
    assert watcher.ready() == []  # consumed once
    # a writer still writing: the header claims more data than is there
    full = tmp_path / "full.wav"
    write_wav(full, tone())
    partial = tmp_path / "b.wav"
    partial.write_bytes(full.read_bytes()[:3000])
    full.unlink()
    assert watcher.ready() == []
    time.sleep(0.25)
    assert [p.name for p in watcher.ready()] == ["b.wav"]  # stable size: handed on (the reader reports it)


def test_spool_watcher_delete_mode(tmp_path: Path) -> None:
    watcher = SpoolWatcher(tmp_path, consume="delete")
    write_wav(tmp_path / "x.wav", tone())
    (path,) = watcher.ready()
    watcher.done(path)
    assert not path.exists()
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(("raw", "published"), [(0.84996, 0.8499), (0.85, 0.85), (0.69999, 0.6999), (0.49999, 0.4999),
                                                (1.0, 1.0), (0.0, 0.0), (0.123456, 0.1234)])
def test_a_published_confidence_never_rounds_up_across_a_threshold(raw: float, published: float) -> None:
    """The reasoner's thresholds (0.5 accept, 0.7 a confirming yes, 0.85 walk unasked) must see what the engine
    decided: a "go" held just below 0.85 (ask) was published as 0.85 and walked."""
    from services.voice.engine import Recognition

    msg = Recognition(Command.GO, "go", raw, "spotter").message()
    assert msg.confidence == published
    assert msg.confidence <= raw


def test_a_microphone_conversion_rounds_and_round_trips() -> None:
    """`rounded_pcm` rounds to the nearest 16-bit step as a sound card does: `from_pcm` then `rounded_pcm` is exact, and
    a quiet noise keeps its level; `to_pcm` (the generator's, truncating) shrinks it by 0.7 dB, as the benches' streams
    did until stop 81."""
    steps = np.arange(-32768, 32768, 7, dtype="<i2").tobytes()
    assert rounded_pcm(from_pcm(steps)) == steps
    assert np.frombuffer(rounded_pcm(np.array([0.4, -0.4, 0.6, -0.6, 1.0, -1.0, 2.0]) / 32768), "<i2").tolist() == [
        0, 0, 1, -1, 1, -1, 2]
    assert np.frombuffer(rounded_pcm(np.array([1.0, -1.0, 1.5])), "<i2").tolist() == [32767, -32768, 32767]
    hiss = np.random.default_rng(0).normal(0.0, 10 / 32768, 160_000)  # -70 dBFS: 10 steps RMS

    def loss_db(pcm: bytes) -> float:
        return float(20 * np.log10(np.std(from_pcm(pcm)) / np.std(hiss)))

    assert abs(loss_db(rounded_pcm(hiss))) < 0.05
    assert -0.9 < loss_db(to_pcm(from_pcm(rounded_pcm(hiss)))) < -0.5
