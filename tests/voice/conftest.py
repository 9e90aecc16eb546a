"""Fixtures of the voice tests."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest
from click.testing import Result


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
