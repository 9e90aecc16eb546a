"""The voice service's pacing of its puts by the reasoner's answers (`services/voice/pacing.py`). The router held back
with the pacer in the loop is tested in tests/platform/test_security.py."""

from __future__ import annotations

import threading
import time

from services.voice.pacing import CommandPacer


def test_with_no_reasoner_answering_commands_go_at_once() -> None:
    pacer = CommandPacer(wait_s=5.0)
    pacer.put(1.0)
    t0 = time.monotonic()
    pacer.turn()
    assert time.monotonic() - t0 < 1.0 and pacer.detail() == {"paced_held": 0, "paced_unanswered": 0}


def test_the_next_command_waits_for_the_answer_to_the_last_then_the_gap() -> None:
    slept: list[float] = []
    pacer = CommandPacer(wait_s=5.0, gap_s=0.002, sleep=slept.append)
    pacer.answered(None)  # a decision came: the reasoner is there
    pacer.put(1.0)
    released = threading.Event()
    waiter = threading.Thread(target=lambda: (pacer.turn(), released.set()))
    waiter.start()
    pacer.answered(2.0)  # another input's decision does not release it
    assert not released.wait(0.2)
    pacer.answered(1.0)
    assert released.wait(2.0)
    waiter.join()
    assert pacer.held == 1 and pacer.unanswered == 0
    assert len(slept) == 1 and 0 < slept[0] <= 0.002  # the router's 1 ms, twice, after the answer


def test_an_unanswered_command_holds_the_next_no_longer_than_wait_s() -> None:
    pacer = CommandPacer(wait_s=0.1)
    pacer.answered(None)
    pacer.put(1.0)
    t0 = time.monotonic()
    pacer.turn()
    assert 0.05 <= time.monotonic() - t0 < 2.0
    assert pacer.held == 1 and pacer.unanswered == 1
    pacer.put(2.0)
    time.sleep(0.15)  # wait_s after its put has passed already: no wait at all
    t1 = time.monotonic()
    pacer.turn()
    assert time.monotonic() - t1 < 0.05 and pacer.unanswered == 2
