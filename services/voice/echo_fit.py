"""A fixed estimate of the way from the robot's loudspeaker to its microphone, fitted by least squares on what the echo
canceller remembers of the robot's voice and subtracted before speexdsp's adaptive filter (round voice49).

speexdsp's filter adapts a little with every frame and, on the voice README's streams, levels off at taking the
robot's voice down by about 20-24 dB however long it has heard it (whether the loudspeaker clips or not); a person's
"stop" at -26 dBFS said over the robot at -12 dBFS then competes with a residue about as loud as itself. The
canceller's memory (`EchoCanceller.memory`: the last 6 s of the microphone's samples and the reference placed before
them) holds enough of the robot's voice to solve for the whole 256 ms impulse response at once (the Wiener-Hopf
equations: the reference's autocorrelation, a Toeplitz matrix, against its cross-correlation with the microphone, by
Levinson's recursion). What that leaves, speexdsp then learns as before; speexdsp keeps its own filter to itself, so the
two stages are cascaded rather than merged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft
from scipy.linalg import solve_toeplitz
from scipy.signal import convolve

TAPS = 4096
"""The fitted impulse response's length: 256 ms at 16 kHz, speexdsp's filter's reach (`echo.FILTER_S`)."""
LOAD = 1e-3
"""Diagonal loading of the autocorrelation (a fraction of the reference's energy): speech's spectrum falls by tens of dB
above 4 kHz and the equations are then near-singular; this keeps the fit from amplifying what the reference hardly
holds."""
MIN_GAIN_DB = 6.0
"""A fit that takes less than this off the memory's own echo is not used: the memory does not hold one way (the robot
was carried to another room mid-memory, the sentences were placed inconsistently) and a wrong estimate would add echo
for speexdsp to take away."""
MIN_S = 1.0
"""Less memory than this (seconds) is not fitted: too few equations for the taps."""


def fit_path(mic: np.ndarray, ref: np.ndarray, rate: int, taps: int = TAPS,
             load: float = LOAD) -> tuple[np.ndarray, float] | None:
    """The impulse response (float, `taps` long) that best predicts `mic` from `ref` (16-bit arrays of one length, the
    reference placed before its echo) and how far it takes `mic` down (dB), or None where there is too little to fit
    (`MIN_S`) or the fit takes less than `MIN_GAIN_DB` off the microphone's samples."""
    x, y = ref.astype(np.float64), mic.astype(np.float64)
    if x.size < MIN_S * rate or not np.any(x):
        return None
    size = next_fast_len(x.size + taps)  # the lags wanted (0 to taps - 1) do not wrap around
    spectrum = rfft(x, size)
    auto = irfft(spectrum * np.conj(spectrum), size)[:taps]
    cross = irfft(rfft(y, size) * np.conj(spectrum), size)[:taps]
    auto[0] *= 1.0 + load
    try:
        h = solve_toeplitz(auto, cross)
    except np.linalg.LinAlgError:
        return None
    left = y - irfft(spectrum * rfft(h, size), size)[: y.size]  # what the fit leaves (its own linear convolution)
    gain_db = 10.0 * np.log10((float(left @ left) + 1.0) / (float(y @ y) + 1.0))
    return (h, round(gain_db, 1)) if gain_db <= -MIN_GAIN_DB else None


@dataclass
class FittedPath:
    """A fitted impulse response run over the reference as it streams: `echo(refs)` is its estimate of what the
    microphone heard of the robot for those samples (the reference before them carried from the last call)."""

    taps: np.ndarray
    _tail: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._tail = np.zeros(self.taps.size - 1)

    def echo(self, refs: np.ndarray) -> np.ndarray:
        x = np.concatenate([self._tail, refs.astype(np.float64)])
        self._tail = x[x.size - self._tail.size :]
        return convolve(x, self.taps, mode="valid")  # direct for a stream's blocks, by FFT for a recalled memory

    def cancel(self, mic: np.ndarray, refs: np.ndarray) -> np.ndarray:
        """`mic` (16-bit) less the estimated echo of `refs` (16-bit, the same length), 16-bit."""
        return np.clip(np.round(mic - self.echo(refs)), -32768, 32767).astype(np.int16)
