"""A simulated microphone for the voice service's `stdin` source: 16 kHz PCM handed to a process's standard input in
30 ms blocks at a microphone's pace, never silent (a faint hiss), with what `sound` adds to each block.

A real sound card hands its blocks over the same way, each once its last sample is captured; the tests and
`bench/voice_stop_latency.py` speak to the running voice service through this, on the production stream path.
"""

from __future__ import annotations

import subprocess
import threading
import time

import numpy as np

from services.voice.audio import SAMPLE_RATE, rounded_pcm

BLOCK_S = 0.03
HISS_DBFS = -70.0


class PacedMicrophone:
    """A microphone that is never silent, handed to a process's stdin (the voice service's `stdin` source) in 30 ms
    blocks at a microphone's pace: a faint hiss (-70 dBFS) and what `sound` adds to each block, each sample rounded to
    16 bits as a sound card rounds it (`rounded_pcm`; the tests' copy before stop 91 truncated toward zero). Subclasses
    override `sound` (called with `lock` held, just before its block is handed over); `lock` is re-entrant, so that a
    caller may hold it across several `MixingMicrophone.mix`es placed by one another."""

    def __init__(self, proc: subprocess.Popen[bytes]) -> None:
        self.proc = proc
        self.lock = threading.RLock()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def sound(self, n: int) -> np.ndarray:
        """Up to `n` samples to add to the next block; called with `lock` held."""
        return np.zeros(0)

    def _run(self) -> None:
        assert self.proc.stdin is not None
        rng, block, start, k = np.random.default_rng(1), int(BLOCK_S * SAMPLE_RATE), time.monotonic(), 0
        while not self.stop.is_set():
            x = rng.normal(0.0, 10 ** (HISS_DBFS / 20), block)
            with self.lock:
                part = self.sound(block)
            x[: part.size] += part
            try:
                self.proc.stdin.write(rounded_pcm(np.clip(x, -1.0, 1.0)))
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError):
                return
            k += 1
            time.sleep(max(0.0, start + k * BLOCK_S - time.monotonic()))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)


class MixingMicrophone(PacedMicrophone):
    """The hiss and whatever is `mix`ed in, each from a moment on (sounds that overlap add up, as in a room); `marks`
    names samples of the stream, and `times` says when the block holding each was handed over (wall clock)."""

    def __init__(self, proc: subprocess.Popen[bytes]) -> None:
        self.ahead = np.zeros(0)
        self.handed = 0
        """Samples handed over (or about to be: `sound` is called just before its block is written)."""
        self.marks: dict[str, int] = {}
        self.times: dict[str, float] = {}
        super().__init__(proc)

    def mix(self, x: np.ndarray, after_s: float = 0.0) -> int:
        """`x` added from `after_s` after the next block's first sample; the stream's index of its first sample."""
        at = int(after_s * SAMPLE_RATE)
        with self.lock:
            if self.ahead.size < at + x.size:
                self.ahead = np.concatenate([self.ahead, np.zeros(at + x.size - self.ahead.size)])
            self.ahead[at : at + x.size] += x
            return self.handed + at

    def sound(self, n: int) -> np.ndarray:
        self.handed += n
        now = time.time()
        for name, index in list(self.marks.items()):
            if index < self.handed:
                self.times[name] = now
                del self.marks[name]
        part, self.ahead = self.ahead[:n], self.ahead[n:]
        return part
