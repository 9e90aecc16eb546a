"""The hand-over from the launcher's pipe readers and the spy's Zenoh callbacks to a terminal that may be paused."""

from __future__ import annotations

import threading

from services.cli.backlog import Backlog


def test_a_paused_consumer_never_holds_up_the_producer_and_hears_what_it_lost() -> None:
    release, got = threading.Event(), []

    def paused_terminal(line: str) -> None:
        release.wait()
        got.append(line)

    backlog: Backlog[str] = Backlog(paused_terminal, lambda n: got.append(f"{n} dropped"), capacity=100, name="t")
    producer = threading.Thread(target=lambda: [backlog.put(f"line {i}") for i in range(250)])
    producer.start()
    producer.join(5)
    assert not producer.is_alive()  # every item was taken while the consumer was blocked
    release.set()
    backlog.close()
    kept = [line for line in got if line.startswith("line")]  # 100 waited, and one was with the consumer if quick
    assert kept == [f"line {i}" for i in range(len(kept))] and len(kept) in (100, 101)
    assert [line for line in got if line.endswith("dropped")] == [f"{250 - len(kept)} dropped"]


def test_a_closed_output_loses_only_its_item_and_close_delivers_what_waits() -> None:
    got: list[int] = []

    def deliver(n: int) -> None:
        if n == 1:
            raise BrokenPipeError
        got.append(n)

    backlog: Backlog[int] = Backlog(deliver, lambda n: None, capacity=10, name="t")
    for n in range(4):
        backlog.put(n)
    backlog.close()
    assert got == [0, 2, 3]


def test_close_gives_up_on_a_consumer_that_never_returns() -> None:
    stuck = threading.Event()
    backlog: Backlog[int] = Backlog(lambda _n: stuck.wait(), lambda n: None, capacity=1, name="t")
    for n in range(3):
        backlog.put(n)  # one with the consumer, one waiting, one dropped
    backlog.close(timeout=0.2)  # returns though the queue is full and the consumer stuck
    stuck.set()
