"""The voice service's pacing of its puts by the reasoner's answers (`services/voice/pacing.py`), on a made-up clock.
The router held back with the pacer in the loop is tested in tests/platform/test_security.py."""

from __future__ import annotations

from collections.abc import Iterable

from services.voice.pacing import CommandPacer


class Bus:
    """Decisions that come at given times on a clock that the pacer's sleeps move on."""

    def __init__(self, answers: dict[float, float | None] | None = None) -> None:
        self.now = 0.0
        self.answers = dict(answers or {})  # at this time, a decision caused by this stamp
        self.slept: list[float] = []

    def clock(self) -> float:
        return self.now

    def sleep(self, s: float) -> None:
        self.slept.append(s)
        self.now += s

    def receive(self) -> Iterable[float | None]:
        due = sorted(t for t in self.answers if t <= self.now)
        return [self.answers.pop(t) for t in due]

    def pacer(self) -> CommandPacer:
        return CommandPacer(self.receive, clock=self.clock, sleep=self.sleep)


def test_with_no_reasoner_answering_commands_go_at_once() -> None:
    bus = Bus()
    pacer = bus.pacer()
    pacer.put(1.0)
    pacer.turn()
    assert bus.now == 0.0 and pacer.detail() == {"paced_held": 0, "paced_unanswered": 0}


def test_the_next_command_waits_for_the_answer_to_the_last_then_the_gap() -> None:
    bus = Bus({0.0: None, 0.1: 2.0, 0.25: 1.0})  # a decision at once (the reasoner is there), another input's, ours
    pacer = bus.pacer()
    pacer.put(1.0)
    pacer.turn()
    assert 0.25 <= bus.now <= 0.25 + pacer.poll_s + pacer.gap_s  # not released by the other input's decision
    assert bus.slept[-1] <= pacer.gap_s + 1e-9  # then the gap: twice the router's 1 ms
    assert pacer.held == 1 and pacer.unanswered == 0


def test_an_answer_already_back_costs_at_most_the_gap_and_nothing_a_word_later() -> None:
    bus = Bus({0.01: 1.0, 1.01: 2.0})
    pacer = bus.pacer()
    pacer.put(1.0)
    bus.now = 0.1  # a burst: the next decoded 0.1 s after
    pacer.turn()
    assert 0.1 < bus.now <= 0.1 + pacer.gap_s + 1e-9 and pacer.held == 0
    bus.now = 1.0
    pacer.put(2.0)
    bus.now = 1.6  # a word later: no gap either
    pacer.turn()
    assert bus.now == 1.6 and pacer.held == 0 and pacer.unanswered == 0


def test_an_unanswered_command_holds_the_next_no_longer_than_wait_s_after_its_put() -> None:
    bus = Bus({0.0: None})
    pacer = bus.pacer()
    pacer.put(1.0)
    pacer.turn()
    assert pacer.wait_s <= bus.now <= pacer.wait_s + pacer.poll_s
    assert pacer.held == 1 and pacer.unanswered == 1
    pacer.put(2.0)
    bus.now += 1.0  # wait_s after its put has passed already: no wait at all
    t = bus.now
    pacer.turn()
    assert bus.now == t and pacer.held == 1 and pacer.unanswered == 2
