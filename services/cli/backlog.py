"""A hand-over to a slow consumer that never makes the producer wait.

The launcher reads the services' output and the spy receives the bus's messages; both then write to a terminal,
and a terminal can stop taking text (paused with Ctrl-S, a pager nobody scrolls). Had the reading waited for it:
- the services' pipes would fill, and each service would stop at its next log line, whatever it was doing (the
  reasoner logs its decisions);
- the spy's Zenoh callback would stop taking messages, and the router would hold back the robot's blocking
  messages (motion goals) for the client that no longer reads (`services/runtime/config.py`, `ROUTER_TRANSPORT`).
So items wait here, up to `capacity`; past that they are dropped and counted, and the count is handed on once the
consumer takes items again.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")

_CLOSED = object()


class Backlog(Generic[T]):
    """`put` never waits; one thread hands the items to `deliver` in order, and `on_dropped(n)` before the next
    item after `n` were dropped. `deliver` raising OSError or ValueError (its output closed) loses that item only."""

    def __init__(self, deliver: Callable[[T], None], on_dropped: Callable[[int], None], *, capacity: int,
                 name: str) -> None:
        self._deliver = deliver
        self._on_dropped = on_dropped
        self._waiting: queue.Queue[object] = queue.Queue(capacity)
        self._dropped = 0
        self._count_lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def put(self, item: T) -> None:
        try:
            self._waiting.put_nowait(item)
        except queue.Full:
            with self._count_lock:
                self._dropped += 1

    def close(self, timeout: float = 2.0) -> None:
        """Deliver what is waiting, giving up after about `timeout` s for each of the two steps (the consumer may
        still be blocked)."""
        try:
            self._waiting.put(_CLOSED, timeout=timeout)
        except queue.Full:
            return
        self._thread.join(timeout)

    def _run(self) -> None:
        while True:
            item = self._waiting.get()
            try:
                if self._dropped:
                    with self._count_lock:
                        dropped, self._dropped = self._dropped, 0
                    self._on_dropped(dropped)
                if item is _CLOSED:
                    return
                self._deliver(item)  # type: ignore[arg-type]
            except (OSError, ValueError):  # the output was closed (a pager quit): the producer goes on regardless
                pass
