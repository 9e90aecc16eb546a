"""A voice that cannot speak on this machine stops a training run, and the bench's compared rows, with a message that
names it and what to install, instead of dropping all of its clips unnoticed (round voice23 found the training splits
rendered without Festival, MBROLA and RHVoice on a fresh machine: every clip of those voices had been dropped as a
word the voice could not say)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bench import voice_bench
from services.voice.training import dataset, tts
from services.voice.training.dataset import OTHER, Recipe

pytestmark = pytest.mark.skipif(not (shutil.which("espeak-ng") and shutil.which("flite")),
                                reason="needs espeak-ng and flite (./run setup installs them)")


@pytest.fixture
def no_flite(monkeypatch: pytest.MonkeyPatch) -> None:
    """flite as if it were not installed."""
    which = shutil.which
    monkeypatch.setattr(tts.shutil, "which", lambda cmd, *a, **k: None if cmd == "flite" else which(cmd, *a, **k))


def test_unavailable_names_each_voice_that_cannot_speak_and_why(no_flite: None) -> None:
    missing = tts.unavailable(["flite:kal16", "flite:kal16@vtl1.10", "espeak:en-us+m3", "mbrola:us9", ""])
    assert set(missing) == {"flite:kal16", "mbrola:us9"}  # a virtual speaker is its voice's; noise has no voice
    assert "apt-get install" in missing["flite:kal16"] and "unknown MBROLA voice" in missing["mbrola:us9"]
    assert tts.unavailable(["espeak:en-us+m3", "flite:kal16"]) == {"flite:kal16": missing["flite:kal16"]}


def test_training_features_refuse_a_voice_that_cannot_speak_before_rendering_anything(
        no_flite: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HRI_VOICE_CACHE", str(tmp_path))
    items = [Recipe("stand", 0, "espeak:en-us+m3", seed=1), Recipe("table", OTHER, "flite:kal16@vtl1.05", seed=2),
             Recipe("white", OTHER, seed=3)]
    with pytest.raises(tts.TtsError, match=r"flite:kal16: flite is not installed \(apt-get install"):
        dataset.indexed_features(items, workers=1, progress=False)
    assert not list(tmp_path.glob("spotter-*"))  # nothing cached: the next run renders them all


def test_bench_stops_on_a_compared_voice_and_leaves_out_an_extra_row(no_flite: None,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    jobs = [(Recipe("stand", 0, "espeak:en-us+m3", seed=1), "clean"), (Recipe("go", 4, "flite:slt", seed=2), "clean"),
            (Recipe("white", OTHER, seed=3), "noise")]
    with pytest.raises(SystemExit, match="flite:slt: flite is not installed"):
        voice_bench._speakable(jobs, required=True)
    assert voice_bench._speakable(jobs, required=False) == [jobs[0], jobs[2]]
    assert "left out, cannot speak here: flite:slt" in capsys.readouterr().out


def test_train_says_which_voice_cannot_speak(monkeypatch: pytest.MonkeyPatch) -> None:
    from typer.testing import CliRunner

    from services.voice.__main__ import app
    from services.voice.training import train

    def refuse(cfg: object, out: object) -> None:
        raise tts.TtsError("these voices cannot speak here ...\n  festival:ked: festival is not installed")

    monkeypatch.setattr(train, "train", refuse)
    result = CliRunner().invoke(app, ["train", "--out", "/dev/null"])
    assert result.exit_code == 1 and "cannot train: these voices" in result.output
    assert "festival:ked: festival is not installed" in result.output


def test_a_command_that_exits_0_without_writing_audio_is_an_error() -> None:
    with pytest.raises(tts.TtsError, match="true wrote no audio"):
        tts._run_to_wav(["true", tts.OUT])


def test_a_command_that_hangs_is_an_error_not_a_crash(monkeypatch: pytest.MonkeyPatch) -> None:
    """A TTS engine that never returns: `subprocess.TimeoutExpired` escaped `unavailable` and stopped the run."""
    monkeypatch.setattr(tts, "TIMEOUT_S", 0.2)
    with pytest.raises(tts.TtsError, match="sleep did not finish within 0.2 s"):
        tts._run(["sleep", "5"])


@pytest.mark.skipif(not shutil.which("text2wave"), reason="needs Festival (apt-get install festival)")
def test_a_festival_voice_that_is_not_installed_is_named_not_a_crash(monkeypatch: pytest.MonkeyPatch) -> None:
    """text2wave asked for a voice it does not have prints a SIOD error and exits 0, writing nothing: before, that
    escaped `unavailable` as a FileNotFoundError and stopped the bench's extra rows instead of leaving one out."""
    monkeypatch.setitem(tts.FESTIVAL_VOICES, "nobody", "nobody_hts")
    monkeypatch.setitem(tts.FESTIVAL_PACKAGES, "nobody", "festvox-nobody")
    missing = tts.unavailable(["festival:nobody"])
    assert "unbound variable" in missing["festival:nobody"] and "apt-get install festvox-nobody" in missing["festival:nobody"]
