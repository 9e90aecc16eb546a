"""`hri view [FILE.mcap]`: the robot in a Rerun viewer, live from the bus or from a recording.

Where the view goes: the native viewer (`rerun` from the `rerun-sdk` wheel, needs a display), the web
viewer (`--web`: a gRPC server that keeps the data and an HTTP server for the viewer's page, for a
browser on this or another machine), or an `.rrd` file (`--save`). The drawing itself is
`services/viewer/scene.py`.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

import rerun as rr
import zenoh
from pydantic import ValidationError

from services.cli.mcapfile import Recorded, model_for_encoding, topic_of
from services.runtime import ServiceContext
from services.viewer.scene import ViewLogger, blueprint

APP_ID = "hri-op2"


class NoDisplay(RuntimeError):
    """The native viewer was asked for on a machine without a display."""


@dataclass(frozen=True)
class Sink:
    web: bool = False
    web_port: int = 9090
    grpc_port: int = 9876
    host: str = "localhost"
    """The name a browser uses for this machine (the web viewer's page connects back to it)."""
    save: Path | None = None


def open_stream(sink: Sink, recording_name: str) -> tuple[rr.RecordingStream, str | None]:
    """A recording stream sent where `sink` says; returns it and the web viewer's address (if any)."""
    rec = rr.RecordingStream(APP_ID, recording_id=None)
    rec.send_recording_name(recording_name)
    if sink.save is not None:
        rec.save(sink.save, default_blueprint=blueprint())
        return rec, None
    if sink.web:
        uri = rec.serve_grpc(grpc_port=sink.grpc_port, default_blueprint=blueprint())
        uri = uri.replace("127.0.0.1", sink.host).replace("localhost", sink.host)
        rr.serve_web_viewer(web_port=sink.web_port, open_browser=False, connect_to=uri)
        return rec, f"http://{sink.host}:{sink.web_port}/?url={quote(uri, safe='')}"
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise NoDisplay("no display for the native viewer: use --web (and open the printed address in a "
                        "browser, here or on another machine) or --save FILE.rrd")
    rec.spawn(default_blueprint=blueprint())
    return rec, None


def log_recording(messages: Iterable[Recorded], logger: ViewLogger) -> int:
    """Draw the messages of a recording (`read_recording`); returns how many were drawn."""
    n = 0
    for m in messages:
        if m.model is None:
            continue
        logger.log(topic_of(m.key), m.decode())
        n += 1
    return n


class LiveFeed:
    """Draws the robot's messages as they come: Zenoh callbacks queue, one thread logs to Rerun."""

    def __init__(self, ctx: ServiceContext, logger: ViewLogger) -> None:
        self.ctx = ctx
        self.logger = logger
        self._queue: queue.Queue[zenoh.Sample | None] = queue.Queue(maxsize=1000)
        self.dropped = 0
        self._thread = threading.Thread(target=self._drain, name="view", daemon=True)
        self._thread.start()
        self._sub = ctx.session.declare_subscriber(ctx.keys.all, self._on_sample)
        ctx.on_close(self.close)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            self._queue.put_nowait(sample)
        except queue.Full:  # the viewer fell behind: drop rather than push back on the bus
            self.dropped += 1

    def _drain(self) -> None:
        while (sample := self._queue.get()) is not None:
            model = model_for_encoding(str(sample.encoding))
            if model is None:
                continue
            try:
                msg = model.model_validate_json(sample.payload.to_bytes())
                self.logger.log(topic_of(str(sample.key_expr)), msg)
            except ValidationError as exc:
                self.ctx.counters.bump("rejected")
                self.ctx.log.warning("not drawn", key=str(sample.key_expr), error=str(exc.errors()[0]["msg"]))
            except Exception:
                self.ctx.log.exception("drawing failed", key=str(sample.key_expr))

    def close(self) -> None:
        try:
            self._sub.undeclare()
        except Exception:  # the session is already closed
            pass
        self._queue.put(None)
        self._thread.join(5.0)
