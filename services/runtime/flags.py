"""On/off settings read from text (environment variables, `KEY=VALUE` items), the same words everywhere."""

from __future__ import annotations

TRUE_WORDS = ("1", "true", "yes", "on")
FALSE_WORDS = ("0", "false", "no", "off")


def parse_flag(raw: str) -> bool | None:
    """True for 1/true/yes/on, False for 0/false/no/off (any case, surrounding spaces ignored), None for anything
    else: the caller says what the setting is and raises its own error."""
    value = raw.strip().lower()
    if value in TRUE_WORDS:
        return True
    if value in FALSE_WORDS:
        return False
    return None
