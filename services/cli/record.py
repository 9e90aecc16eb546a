"""`hri record FILE.mcap`: every message of one robot into an MCAP file, until Ctrl-C or a duration.

The subscription covers `hri/<robot>/**`. Zenoh callbacks only queue samples; one writer thread
validates each payload against the model its encoding names and writes it (a payload that is not a
valid message of a known model is logged once per key, counted and left out: the file holds only
messages that validate). The queue holds at most `MAX_QUEUED_BYTES` of payloads: when the writer falls
that far behind (a slow disk, a flood), newer samples are dropped, logged once per key and counted, so
that a recording never grows the process's memory without bound. At the end: messages per key,
duration, file size, and what was left out or dropped.
"""

from __future__ import annotations

import queue
import threading
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import zenoh
from pydantic import ValidationError
from rich.table import Table

from schemas.keys import SERVICES, Keys
from services.cli.mcapfile import McapWriter, model_for_encoding
from services.runtime import ServiceContext

_STOP = object()

MAX_QUEUED_BYTES = 256 * 1024 * 1024
"""Payload bytes the recorder queues for its writer at most; beyond it, samples are dropped and counted. A running
robot with previews sends about 1.8 MB a minute (`bench/record_bench.py`), so only a writer stalled for long (a full
or hung disk) or a flood reaches it."""


@dataclass
class RecordSummary:
    path: Path
    counts: Counter[str] = field(default_factory=Counter)
    payload_bytes: Counter[str] = field(default_factory=Counter)
    """JSON bytes recorded per key, before compression."""
    rejected: Counter[str] = field(default_factory=Counter)
    """Samples that were not a valid message of a known model, per key."""
    dropped: Counter[str] = field(default_factory=Counter)
    """Samples dropped because the writer was `MAX_QUEUED_BYTES` behind, per key."""
    first: float | None = None
    last: float | None = None
    started: float = field(default_factory=time.time)
    ended: float | None = None

    @property
    def messages(self) -> int:
        return sum(self.counts.values())

    @property
    def duration_s(self) -> float:
        return (self.ended or time.time()) - self.started

    @property
    def size_bytes(self) -> int:
        return self.path.stat().st_size if self.path.exists() else 0

    def table(self) -> Table:
        table = Table(title=str(self.path), caption=f"{self.messages} messages in {self.duration_s:.1f} s, "
                                                    f"{self.size_bytes / 1024:.1f} KiB")
        for col in ("key", "messages", "rate /s", "JSON KiB", "left out", "dropped"):
            table.add_column(col, justify="left" if col == "key" else "right")
        for key in sorted(set(self.counts) | set(self.rejected) | set(self.dropped)):
            rate = self.counts[key] / self.duration_s if self.duration_s > 0 else 0.0
            table.add_row(key, str(self.counts[key]), f"{rate:.1f}", f"{self.payload_bytes[key] / 1024:.1f}",
                          str(self.rejected[key] or ""), str(self.dropped[key] or ""))
        return table


def without_images(keys: Keys) -> list[str]:
    """Every key of the robot except the preview images (which vision then does not even encode)."""
    p = keys.prefix
    return [keys.vision_marks, keys.vision_scene, *(f"{p}/{s}/**" for s in SERVICES if s != "vision")]


class McapRecorder:
    """Records every sample under `keyexprs` (default: the robot's `hri/<robot>/**`) on `ctx`'s session."""

    def __init__(self, ctx: ServiceContext, path: Path, keyexprs: Sequence[str] | None = None,
                 max_queued_bytes: int = MAX_QUEUED_BYTES) -> None:
        self.ctx = ctx
        self.summary = RecordSummary(path)
        self._writer = McapWriter(path)
        self._queue: queue.SimpleQueue[object] = queue.SimpleQueue()
        self._max_queued = max_queued_bytes
        self._queued = 0  # payload bytes in the queue
        self._queued_lock = threading.Lock()
        self._closed = False
        self._thread = threading.Thread(target=self._drain, name="mcap-writer", daemon=True)
        self._thread.start()
        self._subs = [ctx.session.declare_subscriber(k, self._on_sample) for k in keyexprs or [ctx.keys.all]]

    def _on_sample(self, sample: zenoh.Sample) -> None:
        # On a Zenoh thread: only queue (a slow callback pushes back on the network), or drop when the writer is
        # too far behind (the newest is dropped: what is queued is already in order for the file).
        key, data = str(sample.key_expr), sample.payload.to_bytes()
        with self._queued_lock:
            full = self._queued + len(data) > self._max_queued
            if not full:
                self._queued += len(data)
        if full:
            if not self.summary.dropped[key]:
                self.ctx.log.warning("recorder behind: dropping samples", key=key, queued_bytes=self._queued)
            self.summary.dropped[key] += 1
            self.ctx.counters.bump("dropped")
            return
        self._queue.put((key, str(sample.encoding), data))

    def _drain(self) -> None:
        while True:
            item = self._queue.get()
            if item is _STOP:
                return
            key, encoding, data = item  # type: ignore[misc]
            try:
                self._write(key, encoding, data)
            except Exception:  # one bad message must not end the recording
                self.ctx.log.exception("recording a message failed", key=key)
            finally:
                with self._queued_lock:
                    self._queued -= len(data)

    def _write(self, key: str, encoding: str, data: bytes) -> None:
        s = self.summary
        model = model_for_encoding(encoding)
        if model is None:
            self._reject(key, f"encoding {encoding!r} names no known message model")
            return
        try:
            msg = model.model_validate_json(data)
        except ValidationError as exc:
            self._reject(key, f"invalid {model.__name__}: {exc.errors()[0]['msg']}")
            return
        self._writer.write(key, msg, data)
        s.counts[key] += 1
        s.payload_bytes[key] += len(data)
        s.first = msg.stamp if s.first is None else min(s.first, msg.stamp)
        s.last = msg.stamp if s.last is None else max(s.last, msg.stamp)

    def _reject(self, key: str, why: str) -> None:
        if not self.summary.rejected[key]:
            self.ctx.log.warning("not recorded", key=key, reason=why)
        self.summary.rejected[key] += 1
        self.ctx.counters.bump("rejected")

    def close(self) -> RecordSummary:
        """Stop listening, write what is queued and the file's summary; returns the record summary."""
        if not self._closed:
            self._closed = True
            for sub in self._subs:
                try:
                    sub.undeclare()
                except Exception:  # the session is already closed
                    pass
            self._queue.put(_STOP)
            self._thread.join()
            self._writer.close()
            self.summary.ended = time.time()
        return self.summary


def record(ctx: ServiceContext, path: Path, duration: float | None = None, *, images: bool = True) -> RecordSummary:
    """Record until `ctx` is asked to stop (Ctrl-C, SIGTERM) or `duration` seconds have passed."""
    recorder = McapRecorder(ctx, path, None if images else without_images(ctx.keys))
    ctx.log.info("recording", path=str(path), keys=ctx.keys.all, duration_s=duration)
    try:
        ctx.wait(duration)
    finally:
        summary = recorder.close()
    return summary
