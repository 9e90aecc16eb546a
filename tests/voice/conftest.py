"""Fixtures of the voice tests."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from click.testing import Result

from services.voice.audio import to_pcm
from services.voice.spotter import whisper
from services.voice.spotter.embedders import SHAPES
from services.voice.spotter.head import Head
from services.voice.training import corpus, tts

N = len(corpus.VOCABULARY)
GO = corpus.VOCABULARY.index("go")


def fixed_head(embedding: str, winner: int) -> Head:
    """A head that hears class `winner` (N: "other") in anything, with probability ~1."""
    size = int(np.prod(SHAPES[embedding]))
    bias = np.zeros(N + 1, np.float32)
    bias[winner] = 20.0
    return Head(corpus.VOCABULARY, np.zeros(size, np.float32), np.ones(size, np.float32),
                [np.zeros((size, 2), np.float32), np.zeros((2, N + 1), np.float32)], [np.zeros(2, np.float32), bias],
                np.full(N, 0.5), np.full(N, 0.9), embedding=embedding)


@pytest.fixture(scope="module")
def go_pcm() -> bytes:
    """espeak-ng saying "go", with 0.1 s of silence either side."""
    x = tts.synthesise("go", "espeak:en-us", 1.0, 1.0)
    return to_pcm(np.concatenate([np.zeros(1600), x, np.zeros(1600)]))


@pytest.fixture(scope="module")
def whisper_go(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A head file on Whisper's embedding that is sure of "go" in anything."""
    path = tmp_path_factory.mktemp("heads") / "whisper-go.npz"
    fixed_head(whisper.NAME, GO).save(path)
    return path


@dataclass
class TrainCli:
    """`python -m services.voice train ARGS` with the training itself replaced: `seen` holds the (recipe, output
    path) of every run that got past the option checks."""

    seen: list[tuple[object, object]] = field(default_factory=list)

    def __call__(self, *args: str) -> Result:
        from typer.testing import CliRunner

        from services.voice.__main__ import app

        return CliRunner().invoke(app, ["train", *args])

    @property
    def recipes(self) -> list[object]:
        return [cfg for cfg, _ in self.seen]


@pytest.fixture
def train_cli(monkeypatch: pytest.MonkeyPatch) -> TrainCli:
    from services.voice.training import train

    cli = TrainCli()
    monkeypatch.setattr(train, "train", lambda cfg, out: cli.seen.append((cfg, out)) or {"head": str(out)})
    return cli
