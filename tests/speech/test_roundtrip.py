"""Round trip: the spoken refusal, recognised by pocketsphinx (free-form), says the right words."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from pocketsphinx import Decoder

from services.speech.config import SpeechConfig
from services.speech.tts import EspeakNg
from tests.speech.recognise import make_decoder, transcribe

REFUSAL = "Sorry, I cannot do it."
REFUSAL_WORDS = ["sorry", "i", "cannot", "do", "it"]


@pytest.fixture(scope="module")
def decoder() -> Iterator[Decoder]:
    yield make_decoder()


def is_refusal(words: list[str]) -> bool:
    recall = sum(w in words for w in REFUSAL_WORDS) / len(REFUSAL_WORDS)
    return "sorry" in words and "cannot" in words and recall >= 0.8


def default_engine() -> EspeakNg:
    c = SpeechConfig()
    return EspeakNg(c.voice, c.rate, c.volume)


def test_refusal_round_trips_with_the_default_voice(decoder: Decoder, tmp_path: Path) -> None:
    audio = default_engine().synthesize(REFUSAL, tmp_path / "refusal.wav")
    words = transcribe(decoder, audio.path)
    assert is_refusal(words), words


@pytest.mark.parametrize("text", ["The weather is nice today.", "I will stop now."])
def test_other_sentences_are_not_heard_as_the_refusal(decoder: Decoder, tmp_path: Path, text: str) -> None:
    """The check above can fail: other speech through the same path is not taken for the refusal."""
    audio = default_engine().synthesize(text, tmp_path / "other.wav")
    words = transcribe(decoder, audio.path)
    assert words, "nothing recognised at all"
    assert not is_refusal(words), words
