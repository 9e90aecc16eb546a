"""The robot's own voice: when it was talking, and whether an utterance the microphone heard overlaps that.

On the OP2 the loudspeaker and the microphones share the head, so the microphone hears every sentence the robot says,
louder than any person. Measured (`bench/voice_own.py`): all 102 sentences the reasoner can say are heard as speech,
and 9-17 of them as a command ("stand", "stop", "yes", a "go" asked about). Each sentence that matched no command
would make the reasoner answer "Sorry, I did not understand.", which the microphone hears again, without end.

The speech service says when it talks (`SpeechState.speaking`). `OwnVoice` keeps those spans by the voice process's
own clock (when each state arrived: no clock shared across machines is needed) and answers whether an utterance
overlapped one or the `tail_s` after it. The service does not publish such an utterance, except "stop": a person's
"stop" said over the robot's voice must still stop it, and a stop the robot gave itself is the safe mistake.
A sentence already under way when the voice service subscribed sends no state until it ends: the service asks the
speech service's health once at start-up (`speaking`) and `assume`s what it answers.

`said_stop` (`HRI_VOICE_OWN_STOP=ignore`, off by default): a "stop" whose speech began where the robot itself says
"stop" or "stopped", as the echo canceller placed the sentence, is not published either. Round voice52 (voice README,
stop 97) found it kept 12 of 30 stray "stop"s back but lost 7 of 879 person's "stop"s said over the robot's own word.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from services.voice.echo import Sentence

TAIL_S = 0.25
"""Default seconds after the robot's voice ends during which an utterance that begins is still taken for it. The echo
does not need it: through image-source rooms with the loudspeaker 0.1 m from the microphone (`bench/voice_own.py
--room`, T30 up to 1.5 s), no utterance began after the loudspeaker fell silent (the latest began 0.57 s before), as
the echo of the last word is heard with the word. The tail covers the timing: the state's way over the bus, a sound
card's output buffer, the stream's 30 ms blocks. It is short because a person's quick "yes" to "Shall I walk
forward?" begins a few hundred milliseconds after the question."""
LONGEST_S = 30.0
"""A span still open after this long is taken as ended: a speech service that died mid-sentence does not leave the
robot deaf (the longest sentence the reasoner says lasts about 4 s)."""


OWN_STOP_ENV = "HRI_VOICE_OWN_STOP"
OWN_STOP_DEFAULT = "hear"
"""`HRI_VOICE_OWN_STOP` when unset."""
OWN_STOP_BEFORE_S = 0.2
OWN_STOP_AFTER_S = 0.2
"""An utterance that begins from this long before the robot's own "stop" to this long after it ends is taken for it
(`said_stop`)."""


class OwnVoiceError(ValueError):
    """`HRI_VOICE_OWN_VOICE` is not `ignore`, `hear` or a tail in seconds."""


def tail_from(raw: str | None) -> float | None:
    """`HRI_VOICE_OWN_VOICE`: `ignore` (or unset) -> `TAIL_S`; `hear` -> None (the robot's voice is heard like anyone's);
    seconds from 0 to 5 -> that tail."""
    if raw is None or raw.strip().lower() in ("", "ignore"):
        return TAIL_S
    if raw.strip().lower() == "hear":
        return None
    try:
        value = float(raw)
    except ValueError:
        value = -1.0
    if not 0.0 <= value <= 5.0:  # also NaN
        raise OwnVoiceError(f"HRI_VOICE_OWN_VOICE={raw!r}: 'ignore' (the default, a {TAIL_S} s tail), 'hear', or the "
                            "tail in seconds from 0 to 5 during which the microphone still hears the robot's voice")
    return value


@dataclass
class OwnVoice:
    """When the robot was talking. `heard` is fed from the bus's thread, `overlaps` asked from the listener's."""

    tail_s: float = TAIL_S
    clock: Callable[[], float] = field(default=time.time, repr=False)
    """Seconds, the same clock as the utterances' stamps."""
    _since: float | None = None
    _told = False
    """Whether a state has arrived: from then on the states, newer than any answer to a query, decide."""
    _spans: deque[tuple[float, float]] = field(default_factory=lambda: deque(maxlen=32))
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def heard(self, speaking: bool) -> None:
        """The speech service's state, as it arrives."""
        now = self.clock()
        with self._lock:
            self._told = True
            if speaking and self._since is None:
                self._since = now
            elif not speaking and self._since is not None:
                self._spans.append((self._since, now))
                self._since = None

    def assume(self, speaking: bool) -> None:
        """What the speech service answered when asked at start-up (its health's `speaking`): a sentence it began
        before this process subscribed sends no state until it ends. Ignored once a state has arrived, as a state
        published after the answer may arrive before it; a sentence assumed to be under way is taken to have begun
        now."""
        with self._lock:
            if speaking and not self._told and self._since is None:
                self._since = self.clock()

    def speaking(self) -> bool:
        with self._lock:
            return self._since is not None

    def overlaps(self, start: float, end: float) -> bool:
        """Whether speech heard from `start` to `end` (the same clock) overlapped the robot's voice or its tail."""
        with self._lock:
            spans = list(self._spans)
            if self._since is not None:
                spans.append((self._since, min(self._since + LONGEST_S, max(end, self._since))))
        return any(begin <= end and start <= finish + self.tail_s for begin, finish in spans)


def own_stop_from(raw: str | None) -> bool:
    """`HRI_VOICE_OWN_STOP`: `ignore` -> True (a "stop" that begins where the robot itself says "stop" is not
    published, `said_stop`); `hear` -> False (every "stop" is); unset: `OWN_STOP_DEFAULT`."""
    value = (raw or "").strip().lower() or OWN_STOP_DEFAULT
    if value not in ("ignore", "hear"):
        raise OwnVoiceError(f"{OWN_STOP_ENV}={raw!r}: 'ignore' (a \"stop\" that begins where the robot itself says "
                            "\"stop\" is not published) or 'hear' (every \"stop\" is)")
    return value == "ignore"


def said_stop(sentences: Iterable[Sentence], onset: float, before_s: float = OWN_STOP_BEFORE_S,
              after_s: float = OWN_STOP_AFTER_S) -> bool:
    """Whether an utterance whose speech began at `onset` (wall clock) began where the robot itself said "stop": from
    `before_s` before one of a sentence's `stops` to `after_s` after it, where the sentence's echo was found
    (`Sentence.heard_at`, `echo.EchoCanceller.lock`). A sentence whose echo was not found, or whose words are not
    known, counts for nothing: the utterance is then published, as any "stop" over the robot's voice."""
    return any(s.heard_at + a - before_s <= onset <= s.heard_at + b + after_s
               for s in sentences if s.heard_at is not None for a, b in s.stops)
