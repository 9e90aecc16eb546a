"""Structured logging (structlog) with the service name on every line.

`HRI_LOG_LEVEL` (default `info`) sets the level, `HRI_LOG_FORMAT=json` switches the console
renderer for one JSON object per line.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Mapping

import structlog

_configured = False


class _SafeStderr:
    """stderr that never raises: a service whose log reader died (a pipe to a killed launcher)
    must still be able to shut down cleanly instead of dying on BrokenPipeError."""

    def write(self, text: str) -> int:
        try:
            return sys.stderr.write(text)
        except (OSError, ValueError):
            return 0

    def flush(self) -> None:
        try:
            sys.stderr.flush()
        except (OSError, ValueError):
            pass


LEVELS = ("debug", "info", "warning", "error", "critical")
FORMATS = ("console", "json")


def settings_error(env: Mapping[str, str] = os.environ) -> str | None:
    """One line naming a bad `HRI_LOG_LEVEL` or `HRI_LOG_FORMAT` (logging then falls back to the
    defaults; a service refuses to start with it), or None."""
    level, fmt = env.get("HRI_LOG_LEVEL"), env.get("HRI_LOG_FORMAT")
    if level and level.lower() not in (*LEVELS, "warn"):
        return f"HRI_LOG_LEVEL={level!r} is not a level: use one of {', '.join(LEVELS)}"
    if fmt and fmt not in FORMATS:
        return f"HRI_LOG_FORMAT={fmt!r} is not a format: use one of {', '.join(FORMATS)}"
    return None


def configure_logging(level: str | None = None, fmt: str | None = None) -> None:
    global _configured
    level_name = (level or os.environ.get("HRI_LOG_LEVEL") or "info").upper()
    numeric = logging.getLevelName(level_name)
    if not isinstance(numeric, int):
        numeric = logging.INFO
    fmt = fmt or os.environ.get("HRI_LOG_FORMAT") or "console"
    renderer: structlog.typing.Processor
    if fmt == "json":  # anything else: the console format (a service refuses bad values at start)
        renderer = structlog.processors.JSONRenderer()
    else:
        renderer = structlog.dev.ConsoleRenderer(colors=False, pad_event_to=32)
    structlog.configure(
        processors=[
            structlog.contextvars.merge_contextvars,
            structlog.processors.add_log_level,
            structlog.processors.TimeStamper(fmt="%H:%M:%S.%f", utc=False),
            structlog.processors.StackInfoRenderer(),
            structlog.processors.format_exc_info,
            renderer,
        ],
        wrapper_class=structlog.make_filtering_bound_logger(numeric),
        logger_factory=structlog.PrintLoggerFactory(_SafeStderr()),  # type: ignore[arg-type]
        cache_logger_on_first_use=False,
    )
    _configured = True


def get_logger(service: str, **context: object) -> structlog.typing.FilteringBoundLogger:
    if not _configured:
        configure_logging()
    return structlog.get_logger().bind(service=service, **context)
