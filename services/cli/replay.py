"""`hri replay FILE.mcap`: publish a recording's inputs again, with their original timing.

Inputs are what the robot perceives: the marks vision saw and the commands voice heard. Replayed
into a fresh robot (or a fresh reasoner), they give the same decisions; `--check` compares the
decisions made now with the recorded ones, which turns a recorded field incident into a regression
test. `--all` replays every recorded key (to feed a viewer or another tool; do not do that into a
running robot, whose own services publish those keys). Keys are moved to the target robot's prefix,
and every message gets a fresh `stamp` (its publish time) and the replaying publisher's `seq`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

from pydantic import ValidationError

from schemas.messages import Decision, Header
from services.cli.mcapfile import Recorded, RecordingError, topic_of
from services.runtime import ServiceContext, TypedPublisher

INPUT_TOPICS: tuple[str, ...] = ("vision/marks", "voice/command")
"""The keys (after `hri/<robot>/`) that are the robot's inputs."""
MATCH_WAIT_S = 3.0
"""How long to wait for a subscriber of each replayed key before starting (Zenoh drops puts that
no subscriber has been matched to yet)."""


def select(messages: Iterable[Recorded], *, all_keys: bool = False) -> list[Recorded]:
    """The messages to replay: the inputs (or every known model's messages with `all_keys`)."""
    return [m for m in messages if m.model is not None and (all_keys or topic_of(m.key) in INPUT_TOPICS)]


Signature = tuple[str | None, str, str, str | None, str]
"""What a decision decided: (command, verdict, reason, action, situation)."""


def signature(d: Decision) -> Signature:
    return (d.command.value if d.command else None, d.verdict.value, d.reason.value,
            d.action.value if d.action else None, d.situation.value)


def recorded_decisions(messages: Iterable[Recorded]) -> list[Decision]:
    """The recorded decisions; RecordingError if one is not a valid `Decision` of today's contract."""
    out = []
    for m in messages:
        if m.model is Decision and topic_of(m.key) == "reasoner/decision":
            try:
                out.append(Decision.model_validate_json(m.data))
            except ValidationError as exc:
                raise RecordingError(f"a recorded decision is not valid today: {exc.errors()[0]['msg']}") from None
    return out


def compare(expected: Sequence[Decision], got: Sequence[Decision]) -> list[str]:
    """Differences between two decision sequences, one line each (empty: the same decisions)."""
    a, b = [signature(d) for d in expected], [signature(d) for d in got]
    problems = [f"decision {i + 1}: recorded {_fmt(x)}, replayed {_fmt(y)}"
                for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y]
    for i in range(len(b), len(a)):
        problems.append(f"decision {i + 1}: recorded {_fmt(a[i])}, replayed nothing")
    for i in range(len(a), len(b)):
        problems.append(f"decision {i + 1}: replayed {_fmt(b[i])}, not in the recording")
    return problems


def _fmt(s: Signature) -> str:
    command, verdict, reason, action, situation = s
    return f"{command or '(mark)'} -> {verdict} {reason}, action {action or '-'}, {situation}"


@dataclass
class ReplayResult:
    published: int = 0
    seconds: float = 0.0
    unmatched: list[str] = field(default_factory=list)
    """Keys that had no subscriber when the replay started."""
    interrupted: bool = False
    skipped: int = 0
    """Recorded messages that are not valid messages of today's models (logged, not published)."""


class Replayer:
    """Publishes recorded messages on `ctx`'s robot at their recorded pace, divided by `rate`
    (`rate=0`: as fast as possible)."""

    def __init__(self, ctx: ServiceContext, messages: Sequence[Recorded], *, rate: float = 1.0) -> None:
        if rate < 0:
            raise ValueError("rate must be 0 (as fast as possible) or positive")
        self.ctx = ctx
        self.messages = list(messages)
        self.rate = rate
        self._pubs: dict[str, TypedPublisher[Header]] = {}
        for m in self.messages:
            key = f"{ctx.keys.prefix}/{topic_of(m.key)}"
            if key not in self._pubs and m.model is not None:
                self._pubs[key] = ctx.publisher(key, m.model, block=True)

    def wait_matched(self, timeout: float = MATCH_WAIT_S) -> list[str]:
        """Wait until every replayed key has a subscriber; returns the keys that still have none."""
        deadline = time.monotonic() + timeout
        while True:
            missing = [k for k, p in self._pubs.items() if not p.matched]
            if not missing or time.monotonic() >= deadline or self.ctx.wait(0.05):
                return missing

    def run(self, on_publish: Callable[[Recorded, Header], None] | None = None) -> ReplayResult:
        result = ReplayResult(unmatched=self.wait_matched())
        if not self.messages:
            return result
        t_first = self.messages[0].log_time
        start = time.monotonic()
        for m in self.messages:
            if self.rate > 0:
                delay = start + (m.log_time - t_first) / self.rate - time.monotonic()
                if delay > 0 and self.ctx.wait(delay):
                    result.interrupted = True
                    break
            elif self.ctx.stopping.is_set():
                result.interrupted = True
                break
            try:
                msg = m.decode()
            except ValidationError as exc:  # recorded by an older or newer version of the contract
                result.skipped += 1
                self.ctx.counters.bump("rejected")
                self.ctx.log.warning("not replayed", key=m.key, error=str(exc.errors()[0]["msg"]))
                continue
            msg.stamp = time.time()
            self._pubs[f"{self.ctx.keys.prefix}/{topic_of(m.key)}"].put(msg)
            result.published += 1
            if on_publish is not None:
                on_publish(m, msg)
        result.seconds = time.monotonic() - start
        return result


class DecisionWatch:
    """Collects the decisions the robot makes while a replay runs."""

    def __init__(self, ctx: ServiceContext) -> None:
        self.decisions: list[Decision] = []
        self._cond = threading.Condition()
        ctx.subscribe(ctx.keys.reasoner_decision, Decision, self._add)

    def _add(self, d: Decision) -> None:
        with self._cond:
            self.decisions.append(d)
            self._cond.notify_all()

    def settle(self, count: int, quiet_s: float, timeout: float) -> list[Decision]:
        """Wait until `count` decisions came and then none for `quiet_s`; with fewer, give up after
        three times that without a new one (or once `timeout` has passed)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while time.monotonic() < deadline:
                n = len(self.decisions)
                patience = quiet_s if n >= count else 3 * quiet_s
                self._cond.wait(min(patience, max(0.0, deadline - time.monotonic())))
                if len(self.decisions) == n:
                    break
            return list(self.decisions)
