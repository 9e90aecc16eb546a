"""What text the service agrees to speak: one clean line, not empty, not absurdly long."""

from __future__ import annotations

import re

_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


class TextRejected(ValueError):
    """The request's text will not be spoken; the message says why."""


def clean_text(raw: str, max_chars: int) -> str:
    """Control characters become spaces and runs of whitespace one space; then the text is checked."""
    text = " ".join(_CONTROL.sub(" ", raw).split())
    if not text:
        raise TextRejected("empty text")
    if len(text) > max_chars:
        raise TextRejected(f"text too long: {len(text)} characters, the limit is {max_chars}")
    if not any(c.isalnum() for c in text):
        raise TextRejected(f"nothing to say in {text[:40]!r}: no letters or digits")
    return text
