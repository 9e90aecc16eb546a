"""k-of-n temporal filter: a mark is confirmed once seen in at least k of the last n frames.

Per shape, not per position: the robot only cares whether an X, O or triangle is being held up.
A mark first seen at frame t is confirmed at frame t + k - 1 at the earliest (k - 1 frame periods
of latency); it stays confirmed until it has been missing for n - k + 1 frames. One or two noisy
frames (up to k - 1 in any n) neither raise nor drop a mark.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from schemas.messages import Shape
from services.vision.detector import Detection


@dataclass(frozen=True)
class DebounceConfig:
    k: int = 3
    n: int = 5

    def __post_init__(self) -> None:
        if not 1 <= self.k <= self.n:
            raise ValueError(f"debounce needs 1 <= k <= n, got k={self.k} n={self.n}")

    @classmethod
    def parse(cls, text: str) -> DebounceConfig:
        """`"3/5"` -> k=3, n=5."""
        try:
            k, n = (int(p) for p in text.split("/"))
        except ValueError:
            raise ValueError(f"debounce must look like K/N (e.g. 3/5), got {text!r}") from None
        return cls(k, n)

    def __str__(self) -> str:
        return f"{self.k}/{self.n}"


class Debouncer:
    """Feed every frame's detections; get back the confirmed marks."""

    def __init__(self, config: DebounceConfig | None = None) -> None:
        self.config = config or DebounceConfig()
        self._history: dict[Shape, deque[Detection | None]] = {s: deque(maxlen=self.config.n) for s in Shape}

    def update(self, detections: list[Detection]) -> list[Detection]:
        confirmed: list[Detection] = []
        for shape, history in self._history.items():
            mine = [d for d in detections if d.shape == shape]
            history.append(max(mine, key=lambda d: d.confidence) if mine else None)
            hits = [d for d in history if d is not None]
            if len(hits) >= self.config.k:
                latest = hits[-1]
                mean_conf = sum(d.confidence for d in hits) / len(hits)
                confirmed.append(Detection(shape, mean_conf, latest.box))
        return confirmed

    def reset(self) -> None:
        for history in self._history.values():
            history.clear()
