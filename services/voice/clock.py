"""When a live stream's samples were captured, on the wall clock.

A microphone's blocks wait in a queue (up to 6 s, `mic.mic_chunks`) and a pipe's in its buffer whenever the listener
falls behind, so the time a block is read says little about when it was heard. But no block is read before it was
captured, and a listener that keeps up reads some of them at once: over the last `window_s`, the least-delayed block
gives the stream's offset from the wall clock (capture time = stream time + offset) to within a block. The window
(wall-clock seconds) follows a sound card's clock drift (about 0.1 ms a second) and forgets the offset of before a gap
in the stream (dropped blocks, a paused pipe), after which it is larger."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class StreamClock:
    window_s: float = 10.0
    clock: Callable[[], float] = field(default=time.time, repr=False)
    _offsets: deque[tuple[float, float]] = field(default_factory=deque)
    """(when read, offset) of the blocks read within `window_s` that could still be the least delayed; offsets
    increasing."""

    def heard(self, stream_s: float) -> None:
        """The stream has been read up to `stream_s` seconds (the end of the block just read), now."""
        now = self.clock()
        offset = now - stream_s
        while self._offsets and self._offsets[-1][1] >= offset:
            self._offsets.pop()
        while self._offsets and self._offsets[0][0] < now - self.window_s:
            self._offsets.popleft()
        self._offsets.append((now, offset))

    def wall(self, stream_s: float) -> float | None:
        """When the sample at `stream_s` was captured (UNIX seconds); None before any block."""
        return self._offsets[0][1] + stream_s if self._offsets else None
