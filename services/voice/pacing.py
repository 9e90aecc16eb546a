"""Put a command only once the router has passed the one before.

The router drops a put on `voice/command` that reaches it within 1 ms of the last one it let through from the same
session (`schemas.access.RATE_LIMITS`, Zenoh downsampling, against floods). A router that the machine's scheduler
holds back receives puts sent tens of ms apart together, and keeps only the first: with the router paused for
200 ms, 1 of 3 commands put 30 ms apart arrived (stop 120, `docs/experiments/scripts/stop120_router_pause.py`), and
a spool of WAVs decoded back to back lost a command that way in CI.

The reasoner answers every command it is given with a `Decision` whose `cause_stamp` is the command's `stamp`. Once
that answer is back the router has passed the command, and a put made `gap_s` later reaches it outside the limit.
So the voice service puts its next command only after the answer to its last one, or `wait_s` after that put if
no answer comes (a reasoner that is down or shedding a flood): live speech, a word or more apart, never waits. It
paces only once a decision has come at all: with no reasoner on the bus (a bench, the service run alone) nothing
would answer, and commands go at once as before.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

WAIT_S = 0.5
"""The longest a command waits for the answer to the one before it (from that one's put)."""
GAP_S = 0.002
"""After the answer, the wait before the next put: twice the router's 1 ms (`schemas.access.RATE_LIMITS`)."""


@dataclass
class CommandPacer:
    """Holds each command until the reasoner has answered the previous one (thread-safe)."""

    wait_s: float = WAIT_S
    gap_s: float = GAP_S
    clock: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep
    held: int = 0
    """Commands that waited for the answer to the one before."""
    unanswered: int = 0
    """Commands whose answer had not come `wait_s` after their put (the next one went anyway)."""
    _answering: bool = False
    _awaiting: float | None = None
    _put_at: float = -math.inf
    _answered_at: float = -math.inf
    _cond: threading.Condition = field(default_factory=threading.Condition)

    def turn(self) -> None:
        """Block until the next command may be put."""
        with self._cond:
            if not self._answering:
                return
            if self._awaiting is not None:
                self.held += 1
            deadline = self._put_at + self.wait_s
            while self._awaiting is not None:
                left = deadline - self.clock()
                if left <= 0:
                    self.unanswered += 1
                    self._awaiting = None
                    break
                self._cond.wait(left)
            gap = self._answered_at + self.gap_s - self.clock()
        if gap > 0:
            self.sleep(gap)

    def put(self, stamp: float) -> None:
        """A command with this `stamp` is about to be put (called before the put: its answer can come at once)."""
        with self._cond:
            self._awaiting = stamp
            self._put_at = self.clock()

    def answered(self, cause_stamp: float | None) -> None:
        """A decision came back; the one that answers the awaited command lets the next go."""
        with self._cond:
            self._answering = True
            if self._awaiting is not None and cause_stamp == self._awaiting:
                self._awaiting = None
                self._answered_at = self.clock()
                self._cond.notify_all()

    def detail(self) -> dict[str, int]:
        with self._cond:
            return {"paced_held": self.held, "paced_unanswered": self.unanswered}
