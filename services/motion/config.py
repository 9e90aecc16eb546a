"""Motion service settings, from the environment and the command line (DESIGN.md, Configuration)."""

from __future__ import annotations

import os
from dataclasses import dataclass

from services.runtime.flags import parse_flag

DEFAULT_PORT = "/dev/ttyUSB0"


class MotionConfigError(ValueError):
    """A setting is unusable; the message says which and how to fix it."""


def _flag(name: str, raw: str) -> bool:
    value = parse_flag(raw)
    if value is not None:
        return value
    raise MotionConfigError(f"{name}={raw!r}: use 1 (simulated OP2 bus) or 0 (the robot on a serial port)")


def _positive(name: str, value: float) -> float:
    if not value > 0:
        raise MotionConfigError(f"{name} must be > 0, got {value}")
    return value


@dataclass(frozen=True)
class MotionSettings:
    port: str = DEFAULT_PORT
    sim: bool = False
    baud: int = 1_000_000
    latency_ms: float = 16.0
    """USB latency allowance in the reply timeout (the SDK's LATENCY_TIMER)."""
    period_s: float = 0.008
    goal_max_age_s: float = 1.0
    renew_timeout_s: float = 2.0
    stand_time_s: float = 1.0
    stride_mm: float = 15.0
    retry_s: float = 2.0
    bus_down_s: float = 3.0
    """Consecutive failed reads for this long: health `failed` and a reconnect."""
    state_period_s: float = 0.15

    @classmethod
    def resolve(
        cls,
        *,
        port: str | None = None,
        sim: bool | None = None,
        **overrides: float,
    ) -> MotionSettings:
        """HRI_MOTION_PORT / HRI_MOTION_SIM, with explicit arguments winning.

        Without HRI_MOTION_SIM: simulate when no port is configured and /dev/ttyUSB0 does not exist.
        """
        env_port = os.environ.get("HRI_MOTION_PORT") or None
        chosen_port = port or env_port
        if sim is None and os.environ.get("HRI_MOTION_SIM", "").strip():
            sim = _flag("HRI_MOTION_SIM", os.environ["HRI_MOTION_SIM"])
        if sim is None:
            sim = chosen_port is None and not os.path.exists(DEFAULT_PORT)
        for name, value in overrides.items():
            _positive(name, float(value))
        return cls(port=chosen_port or DEFAULT_PORT, sim=sim, **overrides)  # type: ignore[arg-type]
