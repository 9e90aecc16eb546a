"""The bounded, ordered queue of utterances waiting to be spoken.

First in, first out. When it is full the oldest waiting utterance is dropped to make room (the
newest reply is the one that matters), and when an utterance's turn comes after it has waited
longer than `max_age_s` it is skipped: a new refusal never waits behind a long backlog.
Ages are measured on this process's monotonic clock from the moment the request was received,
so clock differences between machines do not matter.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Utterance:
    id: str
    text: str
    received: float = field(default_factory=time.monotonic)
    """Monotonic time the request arrived."""
    stamp: float | None = None
    """The request's own `stamp` (publisher's UNIX time), for logs."""

    def age(self, now: float | None = None) -> float:
        return (time.monotonic() if now is None else now) - self.received


@dataclass(frozen=True)
class Skipped:
    """An utterance that will not be spoken, and why."""

    utterance: Utterance
    reason: str  # "queue_full" or "stale"
    age_s: float


class SpeechQueue:
    """Thread-safe FIFO: `put` from subscriber callbacks, `take` from the one speaking worker."""

    def __init__(
        self, maxsize: int, max_age_s: float, *, clock: Callable[[], float] = time.monotonic
    ) -> None:
        if maxsize < 1:
            raise ValueError("maxsize must be at least 1")
        self.maxsize = maxsize
        self.max_age_s = max_age_s
        self._clock = clock
        self._items: deque[Utterance] = deque()
        self._cond = threading.Condition()
        self.dropped_full = 0
        self.dropped_stale = 0

    def __len__(self) -> int:
        with self._cond:
            return len(self._items)

    def put(self, item: Utterance) -> Skipped | None:
        """Append `item`; if the queue was full, drop the oldest waiting item and return it."""
        with self._cond:
            dropped = None
            if len(self._items) >= self.maxsize:
                old = self._items.popleft()
                self.dropped_full += 1
                dropped = Skipped(old, "queue_full", self._clock() - old.received)
            self._items.append(item)
            self._cond.notify()
            return dropped

    def take(self, timeout: float | None = None) -> tuple[Utterance | None, list[Skipped]]:
        """The next fresh utterance (or None after `timeout`), and the stale ones skipped to reach it."""
        deadline = None if timeout is None else self._clock() + timeout
        skipped: list[Skipped] = []
        with self._cond:
            while True:
                while self._items:
                    item = self._items.popleft()
                    age = self._clock() - item.received
                    if age <= self.max_age_s:
                        return item, skipped
                    self.dropped_stale += 1
                    skipped.append(Skipped(item, "stale", age))
                remaining = None if deadline is None else deadline - self._clock()
                if remaining is not None and remaining <= 0:
                    return None, skipped
                self._cond.wait(remaining)

    def clear(self) -> list[Utterance]:
        with self._cond:
            items = list(self._items)
            self._items.clear()
            return items
