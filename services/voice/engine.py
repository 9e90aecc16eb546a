"""What every recogniser returns, and how engines are chosen by name."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol

from schemas.messages import Command, VoiceCommand


@dataclass(frozen=True)
class Recognition:
    """One decoded utterance: the accepted command (or None), what was heard, and why."""

    command: Command | None
    text: str
    confidence: float
    engine: str
    decode_s: float = 0.0
    audio_s: float = 0.0
    detail: dict[str, Any] = field(default_factory=dict)
    """Engine-specific evidence: raw scores and the rule that accepted or rejected."""

    def message(self, stamp: float | None = None) -> VoiceCommand:
        # Four decimals, rounded DOWN: rounding to nearest published a "go" the engine held just below 0.85
        # (0.84996: ask) as 0.85, and the reasoner walked without asking (nor asking the walk gate).
        msg = VoiceCommand(command=self.command, text=self.text, confidence=math.floor(self.confidence * 1e4) / 1e4,
                           engine=self.engine)
        if stamp is not None:
            msg.stamp = stamp
        return msg


class Engine(Protocol):
    name: str

    def recognise(self, pcm: bytes) -> Recognition:
        """Decode one utterance of 16 kHz, 16-bit mono PCM."""
        ...


class EngineError(RuntimeError):
    """An engine that cannot start (missing model, bad configuration)."""


def one_blas_thread() -> int:
    """Pin this process's BLAS (numpy's OpenBLAS) to one thread, and return the most threads any BLAS now uses. The
    spotter multiplies one utterance's small matrices at a time: on stop 67's AVX2 machine one thread, with a test suite
    on both cores, decoded at a real-time factor of 0.088-0.097, two on the quiet machine at 0.088 for twice the CPU,
    and two under that load at 0.148; the robot's other services need the second core."""
    from threadpoolctl import threadpool_info, threadpool_limits

    threadpool_limits(limits=1, user_api="blas")  # for the whole process, not only a `with` block
    return max((int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"), default=1)


ENGINES = ("spotter", "pocketsphinx", "vosk")
DEFAULT_ENGINE = "spotter"


def check_engine_name(name: str) -> None:
    """`EngineError` for a name that no engine has (a configuration error, not a missing model)."""
    if name not in ENGINES:
        raise EngineError(f"unknown engine {name!r}: use one of {', '.join(ENGINES)}")


def make_engine(name: str, *, vosk_model: str | None = None, lexicon_path: str | None = None,
                head_path: str | None = None, walk_gate: str | None = None,
                agree_min: str | float | None = None, decoder: str | bool | None = None,
                stop_in_phrase: str | bool | None = None, stop_in_long: str | bool | None = None,
                warped_look: str | bool | None = None, down_in_phrase: str | bool | None = None) -> Engine:
    """Build an engine by name; `EngineError` says what is missing."""
    from services.voice.lexicon import Lexicon, LexiconError

    check_engine_name(name)
    if name == "spotter":
        from services.voice.engine_spotter import SpotterEngine

        return SpotterEngine.from_path(head_path, walk_gate, agree_min, decoder, stop_in_phrase, stop_in_long,
                                       warped_look, down_in_phrase)

    try:
        lexicon = Lexicon.load(lexicon_path) if lexicon_path else None
    except LexiconError as exc:
        raise EngineError(str(exc)) from None
    if name == "pocketsphinx":
        from services.voice.engine_pocketsphinx import PocketsphinxEngine, PsConfig

        return PocketsphinxEngine(PsConfig(), lexicon=lexicon)
    if name == "vosk":
        from services.voice.engine_vosk import VoskEngine

        return VoskEngine.from_path(vosk_model, lexicon=lexicon)
    raise EngineError(f"unknown engine {name!r}: use one of {', '.join(ENGINES)}")
