"""Speech test helpers: a recorder of `SpeechState`, a request sender and the service's health."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from subprocess import Popen

import pytest

from schemas.messages import SpeechRequest, SpeechState
from services.runtime import ServiceContext
from tests.conftest import wait_for


@dataclass
class StateLog:
    """Every `SpeechState` received, with the local arrival time."""

    items: list[tuple[float, SpeechState]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def add(self, msg: SpeechState) -> None:
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def events(self) -> list[tuple[bool, str | None]]:
        """(speaking, id) in arrival order, without the service's start-up `speaking=False`."""
        with self.lock:
            return [(m.speaking, m.id) for _, m in self.items if m.id is not None]

    def ready(self) -> bool:
        with self.lock:
            return any(m.id is None and not m.speaking for _, m in self.items)

    def times(self, utterance_id: str) -> tuple[float, float]:
        """Arrival times of speaking=True and speaking=False for one id."""
        with self.lock:
            start = next(t for t, m in self.items if m.id == utterance_id and m.speaking)
            end = next(t for t, m in self.items if m.id == utterance_id and not m.speaking)
        return start, end

    def ended(self, *ids: str) -> bool:
        done = {i for speaking, i in self.events() if not speaking}
        return all(i in done for i in ids)


@pytest.fixture
def states(bus: ServiceContext) -> StateLog:
    log = StateLog()
    bus.subscribe(bus.keys.speech_state, SpeechState, log.add)
    return log


@pytest.fixture
def say(bus: ServiceContext) -> Callable[[str, str], SpeechRequest]:
    pub = bus.publisher(bus.keys.speech_say, SpeechRequest)

    def send(utterance_id: str, text: str) -> SpeechRequest:
        return pub.put(SpeechRequest(id=utterance_id, text=text))

    return send


@pytest.fixture
def speech(
    start_service: Callable[..., Popen[bytes]], states: StateLog, tmp_path: Path
) -> Iterator[Callable[..., Popen[bytes]]]:
    """`speech(*args, env=...)` starts the service writing into tmp_path/out and waits until it listens."""

    def start(*args: str, env: dict[str, str] | None = None, wait: bool = True) -> Popen[bytes]:
        proc = start_service("speech", "--out", str(tmp_path / "out"), *args, env=env)
        if wait:
            wait_for(states.ready, timeout=20)
        return proc

    yield start
