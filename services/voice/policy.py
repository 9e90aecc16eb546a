"""The acceptance rule every engine shares: which heard words become a command, with asymmetric caution.

- Exactly one command may be named; an utterance naming two different commands is rejected.
- "go" (the dangerous one: it makes the robot walk) must be the *only* word of the utterance and
  pass the highest threshold. "stop" is the safe one and is accepted inside a phrase ("please stop").
- Each command has its own threshold on the engine's word confidence (0..1).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from schemas.messages import Command
from services.voice.lexicon import Lexicon


@dataclass(frozen=True)
class Word:
    text: str
    confidence: float


@dataclass(frozen=True)
class Verdict:
    command: Command | None
    confidence: float
    reason: str


def default_thresholds(go: float, other: float, stop: float | None = None) -> dict[Command, float]:
    t = {c: other for c in Command}
    t[Command.GO] = go
    if stop is not None:
        t[Command.STOP] = stop
    return t


@dataclass(frozen=True)
class Policy:
    thresholds: Mapping[Command, float] = field(default_factory=lambda: default_thresholds(0.9, 0.6))
    go_alone: bool = True
    """"go" must be the only word heard."""

    def decide(self, words: Sequence[Word], lexicon: Lexicon) -> Verdict:
        named = [(w, lexicon.lookup(w.text)) for w in words]
        hits = [(w, c) for w, c in named if c is not None]
        if not hits:
            best = max((w.confidence for w in words), default=0.0)
            return Verdict(None, best, "no command word")
        commands = {c for _, c in hits}
        if len(commands) > 1:
            return Verdict(None, 0.0, "several commands: " + ",".join(sorted(c.value for c in commands)))
        command = hits[0][1]
        assert command is not None
        conf = min(w.confidence for w, _ in hits)
        if command == Command.GO and self.go_alone and len(words) > 1:
            return Verdict(None, conf, "go with other words")
        need = self.thresholds.get(command, 1.0)
        if conf < need:
            return Verdict(None, conf, f"{command.value} below threshold {need:.2f}")
        return Verdict(command, conf, "accepted")
