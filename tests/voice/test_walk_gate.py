"""The walk gate (`engine_spotter.WalkGate`, round 14b): a "go" heard surely by a head on one speech embedding
walks unasked only if a head on the other embedding is sure of it too. Real embedders on real speech; the heads
are built with fixed outputs so that which of them is sure is known."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from schemas.messages import Command
from services.voice.engine import EngineError, make_engine
from services.voice.engine_spotter import NO_GATE, SpotterEngine, walk_gate_for
from services.voice.spotter import whisper
from services.voice.spotter.embedders import SPEECH_EMBEDDING
from services.voice.spotter.head import SPEECH_EMBEDDING_HEAD, SURE_CONFIDENCE, Head, HeadError
from services.voice.training import corpus
from tests.voice.conftest import GO, N, fixed_head


@pytest.mark.parametrize(("gate_hears", "walks"), [(GO, True), (N, False), (corpus.VOCABULARY.index("no"), False)])
def test_a_sure_go_walks_only_if_the_gate_is_sure_too(tmp_path: Path, go_pcm: bytes, whisper_go: Path,
                                                      gate_hears: int, walks: bool) -> None:
    gate = tmp_path / "gate.npz"
    fixed_head(SPEECH_EMBEDDING, gate_hears).save(gate)
    engine = SpotterEngine.from_path(whisper_go, str(gate))
    assert engine.gate is not None and engine.gate.head.embedding == SPEECH_EMBEDDING
    rec = engine.recognise(go_pcm)
    assert rec.command == Command.GO  # the gate never drops a command: at worst the robot asks
    assert (rec.confidence >= SURE_CONFIDENCE) is walks
    if not walks:
        assert rec.confidence >= 0.5 and "walk gate" in rec.detail["reason"]
    # without the gate the same head walks
    assert SpotterEngine.from_path(whisper_go, NO_GATE).recognise(go_pcm).confidence >= SURE_CONFIDENCE


def test_the_gate_is_not_asked_about_anything_but_a_sure_go(tmp_path: Path, go_pcm: bytes) -> None:
    stop = tmp_path / "stop.npz"
    fixed_head(whisper.NAME, corpus.VOCABULARY.index("stop")).save(stop)
    gate = tmp_path / "gate.npz"
    fixed_head(SPEECH_EMBEDDING, N).save(gate)
    rec = SpotterEngine.from_path(stop, str(gate)).recognise(go_pcm)
    assert rec.command == Command.STOP and rec.confidence >= SURE_CONFIDENCE and "gate" not in rec.detail


def test_default_gate_is_the_shipped_speech_embedding_head_for_another_embedding(whisper_go: Path) -> None:
    gate = walk_gate_for(Head.load(whisper_go))
    assert gate is not None and gate.head.embedding == SPEECH_EMBEDDING
    np.testing.assert_array_equal(gate.head.accept, Head.load(SPEECH_EMBEDDING_HEAD).accept)
    assert walk_gate_for(Head.load(SPEECH_EMBEDDING_HEAD)) is None  # a speech-embedding head: no second opinion
    assert walk_gate_for(Head.load(whisper_go), NO_GATE) is None


def test_a_gate_on_the_heads_own_embedding_or_unreadable_is_refused(tmp_path: Path, whisper_go: Path) -> None:
    with pytest.raises(HeadError, match="must read another embedding"):
        walk_gate_for(Head.load(whisper_go), str(whisper_go))
    bad = tmp_path / "bad.npz"
    bad.write_text("nope")
    with pytest.raises(EngineError, match="not a spotter head"):
        make_engine("spotter", head_path=str(whisper_go), walk_gate=str(bad))


def test_a_bad_walk_gate_setting_exits_2_naming_it(tmp_path: Path) -> None:
    from tests.voice.test_spotter import _cli

    bad = tmp_path / "gate.npz"
    bad.write_text("nope")
    out = _cli("--source", "stdin", env={"HRI_VOICE_WALK_GATE": str(bad)})
    assert out.returncode == 2 and "HRI_VOICE_WALK_GATE" in out.stderr and "not a spotter head" in out.stderr
