"""SIGTERM and Ctrl-C, handled outside the signal handler.

A Python signal handler runs in the main thread between two of its bytecodes: perhaps in the middle of
a log call, which holds the log's write lock (structlog's `PrintLogger` takes a plain, non-reentrant
lock around each line), or inside `Event.wait`, which holds the event's lock for a few bytecodes. A
handler that logged or set an event there would wait forever on its own thread, and so would every later
signal, so the process could then only be killed. That happened: a service signalled as it logged
"no zenoh router yet" never stopped (once, in CI), and one logging in a loop hung on 2 of 8
SIGTERMs (a test here); blocked writing to a full pipe, it hung every time.

So the handler here does nothing, and the main thread is never interrupted. `signal.set_wakeup_fd` has the
interpreter write each signal's number to a pipe the moment it arrives, and a thread reading that pipe does
the work (log, stop) as ordinary code, even while the main thread is busy in native code.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable
from types import FrameType

STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT)


def relay_stop_signals(on_signal: Callable[[signal.Signals], None]) -> None:
    """Call `on_signal(sig)` from a helper thread for each SIGTERM or SIGINT the process receives.

    Call from the main thread; a later call replaces the earlier one's relay. The main thread is
    never interrupted: code that waits must watch what `on_signal` sets (an event, a flag).
    """
    read_end, write_end = os.pipe()  # both closed on exec: children do not inherit them
    os.set_blocking(write_end, False)

    def relay() -> None:
        while data := os.read(read_end, 16):
            for number in data:
                if number in STOP_SIGNALS:
                    on_signal(signal.Signals(number))

    threading.Thread(target=relay, name="signal-relay", daemon=True).start()
    signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
    for sig in STOP_SIGNALS:
        signal.signal(sig, _note_only)


def _note_only(_signum: int, _frame: FrameType | None) -> None:
    """A handler must be installed for the interpreter to write the wakeup byte; it does nothing more."""


def stop_on_signals() -> threading.Event:
    """An event that SIGTERM or Ctrl-C sets, so the caller leaves its loop and closes what it opened.

    Installed explicitly: a process started in the background of a script inherits SIGINT ignored,
    and Python then raises no KeyboardInterrupt; SIGTERM would otherwise end the process without
    closing anything.
    """
    stop = threading.Event()
    relay_stop_signals(lambda _sig: stop.set())
    return stop
