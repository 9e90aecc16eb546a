"""The pitch of synthesised speech, for the TTS engines' tests."""

from __future__ import annotations

import numpy as np


def f0(y: np.ndarray, rate: int = 16000) -> float:
    """Autocorrelation pitch (Hz, 70-400) of the loudest 100 ms of `y`."""
    n = rate // 10
    i = int(np.argmax(np.convolve(y**2, np.ones(n), "valid")))
    seg = y[i : i + n] - y[i : i + n].mean()
    ac = np.correlate(seg, seg, "full")[n:]
    lo, hi = rate // 400, rate // 70
    return rate / (lo + int(np.argmax(ac[lo:hi])))
