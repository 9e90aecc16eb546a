"""The decoder's rescue (`spotter/decoder.py`, `SpotterEngine.decoder`, round voice30): Whisper tiny.en's own decoder,
on the encoder output the head reads, rescues a command the head missed, below the confidence that walks unasked or
confirms a question, and never changes a command the head accepts. Real model, real espeak-ng speech; the heads have
fixed outputs (`fixed_head`), so what the head hears is known and what is tested is the decoder and the policy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from schemas.messages import Command
from services.voice.audio import to_pcm
from services.voice.engine import EngineError, make_engine
from services.voice.engine_spotter import DECODER_ENV, SpotterEngine, decoder_from
from services.voice.spotter import whisper
from services.voice.spotter.decoder import ENDS_AT, RESCUE_AT, RESCUE_CONFIDENCE, FirstWord, Opinion
from services.voice.spotter.embedders import SPEECH_EMBEDDING
from services.voice.spotter.features import centre
from services.voice.spotter.head import SURE_CONFIDENCE
from services.voice.training import corpus, tts
from tests.voice.conftest import GO, N, fixed_head

YES_MIN_CONFIDENCE = 0.7  # knowledge.soar: a "yes" below this cancels a question instead of confirming it


def _said(word: str) -> bytes:
    x = tts.synthesise(word, "espeak:en-us+f2", 1.0, 1.0)
    return to_pcm(np.concatenate([np.zeros(1600), x, np.zeros(1600)]))


@pytest.fixture(scope="module")
def clips() -> dict[str, bytes]:
    return {w: _said(w) for w in ("stop", "go", "yes", "window")}


def _head(tmp_path: Path, winner: int, embedding: str = whisper.NAME) -> Path:
    path = tmp_path / f"{embedding}-{winner}.npz"
    fixed_head(embedding, winner).save(path)
    return path


@pytest.fixture(scope="module")
def engine_other(tmp_path_factory: pytest.TempPathFactory) -> SpotterEngine:
    """The decoder on, beside a head that hears nothing but "other"."""
    return SpotterEngine.from_path(_head(tmp_path_factory.mktemp("h"), N), decoder="on")


def test_the_decoder_writes_the_command_said_first_and_no_command_for_another_word(
        engine_other: SpotterEngine, clips: dict[str, bytes]) -> None:
    assert engine_other.decoder is not None
    embedder = engine_other.embedder
    assert isinstance(embedder, whisper.WhisperEmbedder)
    for word in ("stop", "go", "yes"):
        opinion = engine_other.decoder.of(embedder.encode(centre(clips[word], 0)))
        assert opinion.best == word and opinion.first[word] > RESCUE_AT and opinion.ends > ENDS_AT
        assert max(opinion.first, key=opinion.first.__getitem__) == word
    opinion = engine_other.decoder.of(embedder.encode(centre(clips["window"], 0)))
    assert opinion.best is None and max(opinion.first.values()) < 0.02


def test_every_command_has_a_one_token_spelling(engine_other: SpotterEngine) -> None:
    assert engine_other.decoder is not None
    assert set(engine_other.decoder.spellings) == set(corpus.VOCABULARY)
    assert all(engine_other.decoder.spellings[w] for w in corpus.VOCABULARY)


def test_a_command_the_head_missed_is_rescued_but_never_walks_or_confirms(
        engine_other: SpotterEngine, clips: dict[str, bytes]) -> None:
    for word in ("stop", "go", "yes"):
        rec = engine_other.recognise(clips[word])
        assert rec.command == Command(word) and 0.5 <= rec.confidence <= RESCUE_CONFIDENCE
        assert rec.detail["reason"].startswith("rescued")
    assert engine_other.recognise(clips["go"]).confidence < SURE_CONFIDENCE  # asks
    assert engine_other.recognise(clips["yes"]).confidence < YES_MIN_CONFIDENCE  # confirms no question
    assert engine_other.recognise(clips["window"]).command is None


def test_a_command_the_head_accepts_is_never_changed(tmp_path: Path, clips: dict[str, bytes]) -> None:
    on = SpotterEngine.from_path(_head(tmp_path, GO), "none", decoder="on")  # a head that hears "go" in anything
    off = SpotterEngine.from_path(_head(tmp_path, GO), "none")
    for word in ("window", "stop"):  # the decoder writes no command, or another one
        a, b = on.recognise(clips[word]), off.recognise(clips[word])
        assert a.command == b.command == Command.GO and a.confidence == b.confidence
        assert "decoder" not in a.detail  # nor is it asked


def test_a_head_on_another_embedding_has_no_decoder(tmp_path: Path) -> None:
    engine = SpotterEngine.from_path(_head(tmp_path, N, SPEECH_EMBEDDING), decoder="on")
    assert engine.decoder is None


def test_off_by_default(tmp_path: Path) -> None:
    assert SpotterEngine.from_path(_head(tmp_path, N)).decoder is None


@pytest.mark.parametrize(("raw", "on"), [(None, False), ("", False), ("on", True), ("1", True), ("off", False),
                                         ("no", False), (True, True)])
def test_the_setting(raw: str | bool | None, on: bool) -> None:
    assert decoder_from(raw) is on


def test_a_bad_setting_is_refused_naming_the_variable(tmp_path: Path) -> None:
    with pytest.raises(EngineError, match=DECODER_ENV):
        decoder_from("sometimes")
    with pytest.raises(EngineError, match=DECODER_ENV):
        make_engine("spotter", head_path=str(_head(tmp_path, N)), decoder="sometimes")


def test_a_bad_setting_exits_2_naming_it() -> None:
    from tests.voice.test_spotter import _cli

    out = _cli("--source", "stdin", env={DECODER_ENV: "sometimes"})
    assert out.returncode == 2 and DECODER_ENV in out.stderr


def test_a_model_folder_without_its_tokenizer_is_a_clear_error(engine_other: SpotterEngine, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="tokenizer"):
        FirstWord(engine_other.embedder.ctranslate2_model, str(tmp_path / "tokenizer.json"),  # type: ignore[attr-defined]
                  corpus.VOCABULARY)


def test_the_opinion_s_thresholds() -> None:
    sure = Opinion({"go": 0.9, "stop": 0.05}, "go", 0.8)
    assert sure.rescue() == ("go", pytest.approx(0.5 + (RESCUE_CONFIDENCE - 0.5) * 0.9))
    assert Opinion({"go": 0.9}, "go", 0.5).rescue() is None  # the word runs on: "go" + "at"
    assert Opinion({"go": 0.45}, "go", 0.9).rescue() is None  # not sure enough
    assert Opinion({"go": 0.9}, None, 0.0).rescue() is None  # the greedy first token is no command's
