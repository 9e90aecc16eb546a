"""Counters and latency figures the speech service reports in its `Health.detail`."""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class SpeechStats:
    spoken: int = 0
    interrupted: int = 0
    rejected_text: int = 0
    rejected_unavailable: int = 0
    duplicates: int = 0
    synth_errors: int = 0
    ready_ms: deque[float] = field(default_factory=lambda: deque(maxlen=200))
    """Request received to audio ready (WAV complete), the most recent 200 utterances."""
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def bump(self, name: str) -> None:
        with self._lock:
            setattr(self, name, getattr(self, name) + 1)

    def ready(self, ms: float) -> None:
        with self._lock:
            self.ready_ms.append(ms)

    def summary(self) -> dict[str, Any]:
        with self._lock:
            ready = np.array(self.ready_ms) if self.ready_ms else None
            out: dict[str, Any] = {
                "spoken": self.spoken,
                "interrupted": self.interrupted,
                "rejected_text": self.rejected_text,
                "rejected_unavailable": self.rejected_unavailable,
                "duplicates": self.duplicates,
                "synth_errors": self.synth_errors,
            }
        if ready is not None:
            out["ready_ms_last"] = round(float(ready[-1]), 1)
            out["ready_ms_p50"] = round(float(np.percentile(ready, 50)), 1)
            out["ready_ms_p95"] = round(float(np.percentile(ready, 95)), 1)
        return out
