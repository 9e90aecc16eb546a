"""The robot's traffic in MCAP files: one channel per key, JSON messages with the model's JSON Schema.

A channel's topic is the Zenoh key (`hri/op2/vision/marks`), its message encoding `json`, and its
schema the pydantic model's JSON Schema (`Model.model_json_schema()`, schema encoding `jsonschema`)
under the model's name, the same name the payload's Zenoh encoding carries
(`application/json;MarkObservation`). Foxglove Studio, the `mcap` CLI and any MCAP reader open such a
file as it is. A message's log time and publish time are its `stamp` (nanoseconds), its sequence the
publisher's `seq`.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import CompressionType, Writer

from schemas.messages import MODELS, Header

PROFILE = ""
"""No ROS profile: plain JSON channels (what Foxglove calls a custom profile)."""
LIBRARY = "hri-op2"
CHUNK_BYTES = 256 * 1024
"""Chunk size: what a killed recorder can lose (the summary is written on a clean stop)."""


class RecordingError(ValueError):
    """A file that is not a readable recording; the message names the file and the problem."""


def model_for_encoding(encoding: str) -> type[Header] | None:
    """`application/json;MarkObservation` -> MarkObservation (None for anything else)."""
    kind, _, schema = encoding.partition(";")
    if kind != "application/json":
        return None
    return MODELS.get(schema)


def topic_of(key: str) -> str:
    """`hri/op2/vision/marks` -> `vision/marks` (the key without the robot's prefix)."""
    parts = key.split("/", 2)
    if len(parts) < 3 or parts[0] != "hri":
        raise RecordingError(f"key {key!r} is not under hri/<robot>/")
    return parts[2]


class McapWriter:
    """Writes messages of known models to an MCAP file; registers a schema and channel when first seen."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file: IO[bytes] = path.open("wb")
        self._writer = Writer(self._file, chunk_size=CHUNK_BYTES, compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library=LIBRARY)
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._closed = False

    def write(self, key: str, msg: Header, data: bytes) -> None:
        """Add one message: `data` is its JSON payload as it was on the wire."""
        channel = self._channels.get(key)
        if channel is None:
            channel = self._register(key, type(msg))
        when = int(msg.stamp * 1e9)
        self._writer.add_message(channel, log_time=when, data=data, publish_time=when, sequence=msg.seq)

    def _register(self, key: str, model: type[Header]) -> int:
        name = model.__name__
        schema = self._schemas.get(name)
        if schema is None:
            data = json.dumps(model.model_json_schema(), separators=(",", ":")).encode()
            schema = self._schemas[name] = self._writer.register_schema(name, "jsonschema", data)
        channel = self._channels[key] = self._writer.register_channel(
            topic=key, message_encoding="json", schema_id=schema, metadata={"model": name}
        )
        return channel

    def close(self) -> None:
        """Write the summary and index and close the file. Idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.finish()
        finally:
            self._file.close()


@dataclass(frozen=True)
class Recorded:
    """One message read back from a recording."""

    key: str
    schema: str
    log_time: float
    """UNIX seconds (the message's stamp when it was recorded)."""
    data: bytes
    model: type[Header] | None
    """The model named by the channel's schema, when this version of the code knows it."""

    def decode(self) -> Header:
        if self.model is None:
            raise RecordingError(f"{self.key}: unknown model {self.schema!r}")
        return self.model.model_validate_json(self.data)


_UNREADABLE = (McapError, ValueError, EOFError, struct.error)


def read_recording(path: Path) -> Iterator[Recorded]:
    """Every message of a recording in log-time order; RecordingError if it is not a readable MCAP file.

    A file whose recorder was killed has no summary: it is read from the start, up to its last
    complete chunk.
    """
    try:
        with path.open("rb") as f:
            try:
                messages = list(make_reader(f).iter_messages(log_time_order=True))
            except _UNREADABLE as exc:
                f.seek(0)
                messages = _read_truncated(f, exc)
    except FileNotFoundError:
        raise RecordingError(f"{path}: no such file") from None
    except _UNREADABLE as exc:
        raise RecordingError(f"{path}: not a readable MCAP recording ({exc})") from None
    for schema, channel, message in messages:
        name = schema.name if schema is not None else ""
        yield Recorded(channel.topic, name, message.log_time / 1e9, message.data, MODELS.get(name))


def _read_truncated(f: IO[bytes], first_error: Exception) -> list[tuple[Any, Any, Any]]:
    """The messages of every complete chunk of a file that ends early (no summary, no footer)."""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    out: list[tuple[Any, Any, Any]] = []
    try:
        for record in StreamReader(f, skip_magic=False).records:
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message) and record.channel_id in channels:
                channel = channels[record.channel_id]
                out.append((schemas.get(channel.schema_id), channel, record))
    except _UNREADABLE:
        if not out:
            raise first_error from None
    out.sort(key=lambda item: item[2].log_time)
    return out
