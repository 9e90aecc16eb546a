"""The agreement veto (`SpotterEngine.agree_min`, round voice27): a command the head would publish is published only
if the walk gate's head, on the other speech embedding, gives that same command at least `agree_min`. Real embedders
on real speech; the heads have fixed outputs, so what each of them hears is known."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from schemas.messages import Command
from services.voice.engine import EngineError, make_engine
from services.voice.engine_spotter import AGREE_ENV, NO_GATE, SpotterEngine, agree_min_from
from services.voice.spotter import whisper
from services.voice.spotter.embedders import SPEECH_EMBEDDING
from services.voice.spotter.head import SURE_CONFIDENCE
from services.voice.training import corpus
from tests.voice.conftest import GO, N, fixed_head

STOP = corpus.VOCABULARY.index("stop")
YES = corpus.VOCABULARY.index("yes")


def _gate(tmp_path: Path, winner: int, bias: float = 20.0) -> str:
    """A speech-embedding head hearing `winner` with probability e^bias / (e^bias + N) (N other classes at 0)."""
    head = fixed_head(SPEECH_EMBEDDING, winner)
    head.biases[-1][winner] = bias
    path = tmp_path / f"gate-{winner}-{bias:.3f}.npz"
    head.save(path)
    return str(path)


def _bias_for(p: float) -> float:
    """The bias that gives the winner probability `p` among N + 1 classes."""
    return math.log(p * N / (1 - p))


@pytest.mark.parametrize(("gate_p", "published"), [(0.4, True), (0.2, False)])
def test_a_command_is_published_only_if_the_gate_gives_it_enough(tmp_path: Path, go_pcm: bytes, whisper_go: Path,
                                                                 gate_p: float, published: bool) -> None:
    engine = SpotterEngine.from_path(whisper_go, _gate(tmp_path, GO, _bias_for(gate_p)), agree_min=0.25)
    rec = engine.recognise(go_pcm)
    assert rec.detail["agree"] == pytest.approx(gate_p, abs=1e-3)
    if published:
        assert rec.command == Command.GO and 0.5 <= rec.confidence < SURE_CONFIDENCE  # the gate is not sure: ask
    else:
        assert rec.command is None and rec.confidence <= 0.49 and "below 0.25" in rec.detail["reason"]
        assert rec.text == "go"  # the head's guess is still named


@pytest.mark.parametrize("gate_hears", [N, YES])  # "other", or another command
def test_the_veto_makes_no_question_where_the_other_embedding_hears_something_else(
        tmp_path: Path, go_pcm: bytes, whisper_go: Path, gate_hears: int) -> None:
    rec = SpotterEngine.from_path(whisper_go, _gate(tmp_path, gate_hears), agree_min=0.25).recognise(go_pcm)
    assert rec.command is None and rec.confidence <= 0.49
    # without the veto the same pair asks (the walk gate turns the walk into a question, never drops it)
    rec = SpotterEngine.from_path(whisper_go, _gate(tmp_path, gate_hears), agree_min=0).recognise(go_pcm)
    assert rec.command == Command.GO and 0.5 <= rec.confidence < SURE_CONFIDENCE and "agree" not in rec.detail


def test_where_both_are_sure_the_robot_still_walks(tmp_path: Path, go_pcm: bytes, whisper_go: Path) -> None:
    rec = SpotterEngine.from_path(whisper_go, _gate(tmp_path, GO), agree_min=0.25).recognise(go_pcm)
    assert rec.command == Command.GO and rec.confidence >= SURE_CONFIDENCE and rec.detail["gate"] >= SURE_CONFIDENCE


def test_every_command_is_vetoed_not_only_go(tmp_path: Path, go_pcm: bytes) -> None:
    stop = tmp_path / "stop.npz"
    fixed_head(whisper.NAME, STOP).save(stop)
    assert SpotterEngine.from_path(stop, _gate(tmp_path, STOP), agree_min=0.25).recognise(go_pcm).command == Command.STOP
    assert SpotterEngine.from_path(stop, _gate(tmp_path, N), agree_min=0.25).recognise(go_pcm).command is None


def test_without_a_gate_there_is_no_veto(whisper_go: Path, go_pcm: bytes) -> None:
    engine = SpotterEngine.from_path(whisper_go, NO_GATE, agree_min=0.25)
    assert engine.agree_min == 0.0
    assert engine.recognise(go_pcm).command == Command.GO


@pytest.mark.parametrize("raw", ["1", "1.5", "-0.1", "often"])
def test_a_bad_setting_is_refused_naming_the_variable(raw: str, whisper_go: Path) -> None:
    with pytest.raises(EngineError, match=AGREE_ENV):
        agree_min_from(raw)
    with pytest.raises(EngineError, match=AGREE_ENV):
        make_engine("spotter", head_path=str(whisper_go), agree_min=raw)


def test_the_default_and_zero() -> None:
    assert agree_min_from(None) == agree_min_from("") == 0.0
    assert agree_min_from("0") == 0.0 and agree_min_from("0.25") == 0.25


def test_a_bad_setting_exits_2_naming_it() -> None:
    from tests.voice.test_spotter import _cli

    out = _cli("--source", "stdin", env={AGREE_ENV: "often"})
    assert out.returncode == 2 and AGREE_ENV in out.stderr
