"""Put a command only once the router has passed the one before.

The router drops a put on `voice/command` that reaches it within 1 ms of the last one it let through from the same
session (`schemas.access.RATE_LIMITS`, Zenoh downsampling, against floods). A router that the machine's scheduler
holds back receives puts sent tens of ms apart together, and keeps only the first: with the router paused for
200 ms, 1 of 3 commands put 30 ms apart arrived (stop 120, `docs/experiments/scripts/stop120_router_pause.py`), and
a spool of WAVs decoded back to back lost a command that way in CI.

The reasoner answers every command it is given with a `Decision` whose `cause_stamp` is the command's `stamp`. Once
that answer is back the router has passed the command, and a put made `gap_s` later reaches it outside the limit.
So the voice service puts its next command only after the answer to its last one, or `wait_s` after that put if
no answer comes (a reasoner that is down or shedding a flood). A command `wait_s` or more after the last never waits:
live speech, a word or more apart, is not held at all. It paces only once a decision has come at all: with no
reasoner on the bus (a bench, the service run alone) nothing would answer, and commands go at once as before.

The decisions are taken by the listening thread itself, when it is about to put a command (`ServiceContext.polled`),
so pacing adds no thread and no Zenoh callback to the process. With the subscription first made as a callback (whose
own thread Zenoh starts), the voice service once ended on SIGABRT after SIGTERM ("FATAL: exception not rethrown",
stop 120's CI run; not reproduced in 10 runs): a callback's thread woken while the process exits is the likeliest
cause, and a polled channel has none.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

WAIT_S = 0.5
"""The longest a command waits for the answer to the one before it (from that one's put)."""
GAP_S = 0.002
"""After the answer, the wait before the next put: twice the router's 1 ms (`schemas.access.RATE_LIMITS`)."""
POLL_S = 0.002
"""How often a waiting command looks for its answer."""


@dataclass
class CommandPacer:
    """Holds each command until the reasoner has answered the previous one. One thread: the one that puts."""

    receive: Callable[[], Iterable[float | None]]
    """The `cause_stamp`s of the decisions come since it was last called (never blocking)."""
    wait_s: float = WAIT_S
    gap_s: float = GAP_S
    poll_s: float = POLL_S
    clock: Callable[[], float] = time.monotonic
    sleep: Callable[[float], None] = time.sleep
    held: int = 0
    """Commands that waited for the answer to the one before."""
    unanswered: int = 0
    """Commands put without the answer to the one before: none came within `wait_s` of its put."""
    _answering: bool = False
    _awaiting: float | None = None
    _put_at: float = -math.inf
    _answered_at: float = -math.inf

    def turn(self) -> None:
        """Return when the next command may be put."""
        self._take()
        if not self._answering:
            return
        deadline = self._put_at + self.wait_s
        if self._awaiting is not None and self.clock() < deadline:
            self.held += 1
            while self._awaiting is not None and self.clock() < deadline:
                self.sleep(self.poll_s)
                self._take()
        if self._awaiting is not None:
            self.unanswered += 1
            self._awaiting = None
        if self.clock() < deadline:  # a burst: the router may have passed the last one only just now
            gap = self._answered_at + self.gap_s - self.clock()
            if gap > 0:
                self.sleep(gap)

    def put(self, stamp: float) -> None:
        """A command with this `stamp` is about to be put (its answer can come at once)."""
        self._take()
        self._awaiting = stamp
        self._put_at = self.clock()

    def _take(self) -> None:
        """Note the decisions come: any shows the reasoner answers; the awaited one lets the next command go."""
        for cause in self.receive():
            self._answering = True
            if self._awaiting is not None and cause == self._awaiting:
                self._awaiting = None
                self._answered_at = self.clock()

    def detail(self) -> dict[str, int]:
        return {"paced_held": self.held, "paced_unanswered": self.unanswered}
