"""Asymmetric confirmation: a danger mark acts on its first confident frame, the safe mark only once
it has been seen over several frames.

Stopping is the safe direction and lifting a danger the dangerous one, so the two kinds of mark are
filtered differently, each by a k-of-n window per shape (per shape, not per position: the robot only
cares whether an X, O or triangle is being held up):

- X and TRIANGLE (danger), default 1 of 3: published from the first frame in which the detector
  reports one (no added latency); held for two more frames after it was last seen, so one or two
  dropped detections do not flicker it.
- O (safe), default 3 of 4: published from its third sighting within four frames (two frame periods
  of added latency at the earliest: 67 ms at 30 fps, 133 ms at 15 fps), so a single false O never
  clears a danger; released after two frames without it. And only where no X or triangle was detected
  in any frame of that same window (`Confirmation.clear_of_danger`, round vision31): an O seen beside a
  danger mark that flickers in and out never lifts the danger in a frame where the danger mark happens
  to be missing. Nor may an O that was already confirmed when a danger mark came lift that danger while it
  stays in view (`Confirmation.new_safe_only`, round vision32): only an O shown anew says "safe again".

A mark first seen at frame t is confirmed at frame t + k - 1 at the earliest and stays confirmed
until it has been missing for n - k + 1 frames.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from schemas.messages import Shape
from services.vision.detector import Box, Detection, box_overlap

DANGER_SHAPES = frozenset({Shape.X, Shape.TRIANGLE})
STALE_OVERLAP = 0.3
"""An O detection overlapping a stale O's box by this much (intersection over the smaller box) is that O."""


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


@dataclass(frozen=True)
class Confirmation:
    """The k-of-n windows for danger marks (X, TRIANGLE) and for the safe mark (O)."""

    danger: DebounceConfig = field(default_factory=lambda: DebounceConfig(1, 3))
    safe: DebounceConfig = field(default_factory=lambda: DebounceConfig(3, 4))
    clear_of_danger: bool = True
    """The safe mark is confirmed only if no X or triangle was detected in any frame of its window. On held-out
    clips (bench/vision_clips.py) a clutter letter O beside an X card, with the X missing for three frames, was
    otherwise confirmed in a frame without the X: the reasoner, for which danger wins only within one
    observation, would have lifted the danger while the X was still held up."""

    new_safe_only: bool = True
    """An O confirmed within the safe window's n frames before a frame with an X or triangle detected is stale: O
    detections overlapping it (`STALE_OVERLAP`) do not count towards the O's confirmation, and it follows them,
    until no O has overlapped it for n frames. On held-out clips with a hand (bench/vision_clips.py --hand), a
    clutter O confirmed before a triangle card came lifted the danger once the triangle, drifting out of view,
    was lost for three frames; an O that was there all along is not a person saying "safe again"."""

    stale_held_by_danger: bool = True
    """With `new_safe_only`: a frame with an X or triangle detected does not count towards forgetting a stale O. The
    detector reports only the marks found up to a frame's first danger mark (`DetectorConfig.danger_first`), so an O
    missing from such a frame may not have been looked for. On held-out clips with a hand (seed 3141, clip 390 again,
    with a rolling shutter or automatic exposure alone), four frames of a triangle and no O detected aged the stale O
    out, and the same O, seen again, lifted the danger once the triangle drifted out of view (round vision33)."""

    def for_shape(self, shape: Shape) -> DebounceConfig:
        return self.danger if shape in DANGER_SHAPES else self.safe

    def __str__(self) -> str:
        return f"danger {self.danger}, safe {self.safe}"


@dataclass
class _Stale:
    """An O that was confirmed when a danger mark came (`Confirmation.new_safe_only`)."""

    box: Box
    unseen: int = 0
    """Frames since an O detection last overlapped it."""


class Debouncer:
    """Feed every frame's detections; get back the confirmed marks. A single `DebounceConfig`
    applies the same window to every shape."""

    def __init__(self, config: Confirmation | DebounceConfig | None = None) -> None:
        if isinstance(config, DebounceConfig):
            config = Confirmation(danger=config, safe=config)
        self.config = config or Confirmation()
        self._history: dict[Shape, deque[Detection | None]] = {
            s: deque(maxlen=self.config.for_shape(s).n) for s in Shape
        }
        self._danger: deque[bool] = deque(maxlen=self.config.safe.n)  # a danger mark detected, frame by frame
        self._last_safe: tuple[Box, int] | None = None  # the O confirmed last, and frames since
        self._stale: list[_Stale] = []

    def update(self, detections: list[Detection]) -> list[Detection]:
        confirmed: list[Detection] = []
        danger = any(d.shape in DANGER_SHAPES for d in detections)
        self._danger.append(danger)
        if self.config.new_safe_only:
            detections = self._drop_stale(detections, danger)
        for shape, history in self._history.items():
            mine = [d for d in detections if d.shape == shape]
            history.append(max(mine, key=lambda d: d.confidence) if mine else None)
            hits = [d for d in history if d is not None]
            if shape not in DANGER_SHAPES and self.config.clear_of_danger and any(self._danger):
                continue
            if len(hits) >= self.config.for_shape(shape).k:
                latest = hits[-1]
                mean_conf = sum(d.confidence for d in hits) / len(hits)
                confirmed.append(Detection(shape, mean_conf, latest.box))
        safe = [d.box for d in confirmed if d.shape not in DANGER_SHAPES]
        if safe:
            self._last_safe = (safe[0], 0)
        elif self._last_safe is not None:
            self._last_safe = (self._last_safe[0], self._last_safe[1] + 1)
        return confirmed

    def _drop_stale(self, detections: list[Detection], danger: bool) -> list[Detection]:
        """Mark the O confirmed last as stale when a danger mark comes; the frame's O detections that are a stale
        O are left out (the stale box follows them); a stale box unmatched for the safe window is forgotten."""
        n = self.config.safe.n
        if danger and self._last_safe is not None and self._last_safe[1] < n:
            self._stale.append(_Stale(self._last_safe[0]))
            self._last_safe = None
        if not self._stale:
            return detections
        kept: list[Detection] = []
        if not (danger and self.config.stale_held_by_danger):
            for stale in self._stale:
                stale.unseen += 1
        for d in detections:
            match = None
            if d.shape not in DANGER_SHAPES:
                match = next((st for st in self._stale if box_overlap(d.box, st.box) >= STALE_OVERLAP), None)
            if match is None:
                kept.append(d)
            else:
                match.box, match.unseen = d.box, 0
        self._stale = [st for st in self._stale if st.unseen < n]
        return kept

    def reset(self) -> None:
        for history in self._history.values():
            history.clear()
        self._danger.clear()
        self._last_safe = None
        self._stale.clear()
