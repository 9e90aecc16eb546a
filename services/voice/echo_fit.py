"""A fixed estimate of the way from the robot's loudspeaker to its microphone, fitted by least squares on what the echo
canceller remembers of the robot's voice and subtracted before speexdsp's adaptive filter (round voice49).

speexdsp's filter adapts a little with every frame and, on the voice README's streams, levels off at taking the
robot's voice down by about 20-24 dB however long it has heard it (whether the loudspeaker clips or not); a person's
"stop" at -26 dBFS said over the robot at -12 dBFS then competes with a residue about as loud as itself. The
canceller's memory (`EchoCanceller.memory`: the last 6 s of the microphone's samples and the reference placed before
them) holds enough of the robot's voice to solve for the whole 256 ms impulse response at once (the Wiener-Hopf
equations: the reference's autocorrelation, a Toeplitz matrix, against its cross-correlation with the microphone, by
Levinson's recursion, `solve_toeplitz`). What that leaves, speexdsp then learns as before; speexdsp keeps its own filter
to itself, so the two stages are cascaded rather than merged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft
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


def solve_toeplitz(column: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x with T x = b, T the symmetric positive definite Toeplitz matrix whose first column is `column` (float arrays of
    one length), by Levinson's recursion (Golub and Van Loan, Matrix Computations, algorithm 4.7.3); LinAlgError where T
    is not positive definite.

    The solution scipy.linalg.solve_toeplitz gives (to rounding; tests/voice/test_echo_fit.py holds them together), but
    SciPy's compiled recursion keeps the interpreter's lock for the whole solve: for `TAPS` on a 2-core AVX2 machine,
    7-18 ms idle and 62-69 ms beside another bench (bench/voice_echo_fit.py), longer on a robot's slower computer. A fit runs in the background while the
    service listens, and for that long neither the stream's thread nor the microphone's PortAudio callback could run, as
    a person's "stop" after the robot's sentence was coming in. Here each of the `column.size` steps is a few NumPy
    calls, between which the other threads take their turn; the fit takes 1.5-2 times as long, on its own thread."""
    r = column[1:] / column[0]
    b = b / column[0]
    x, y = np.zeros(b.size), np.zeros(b.size)
    x[0] = b[0]
    if b.size == 1:
        return x
    alpha = y[0] = -r[0]
    beta = 1.0
    for k in range(1, b.size):
        beta *= 1.0 - alpha * alpha  # the leading k x k minor over the (k-1) x (k-1) one: > 0 while T is positive definite
        if not beta > 0.0:
            raise np.linalg.LinAlgError(f"the Toeplitz matrix is not positive definite (step {k})")
        back = r[k - 1 :: -1]
        mu = (b[k] - back @ x[:k]) / beta
        x[:k] += mu * y[k - 1 :: -1]
        x[k] = mu
        if k < b.size - 1:
            alpha = -(r[k] + back @ y[:k]) / beta
            y[:k] += alpha * y[k - 1 :: -1]
            y[k] = alpha
    return x


def fit_path(mic: np.ndarray, ref: np.ndarray, rate: int, taps: int = TAPS, load: float = LOAD,
             solve: Callable[[np.ndarray, np.ndarray], np.ndarray] = solve_toeplitz) -> tuple[np.ndarray, float] | None:
    """The impulse response (float, `taps` long) that best predicts `mic` from `ref` (16-bit arrays of one length, the
    reference placed before its echo) and how far it takes `mic` down (dB), or None where there is too little to fit
    (`MIN_S`) or the fit takes less than `MIN_GAIN_DB` off the microphone's samples. `solve`: the Toeplitz solver
    (bench/voice_echo_fit.py passes SciPy's to compare)."""
    x, y = ref.astype(np.float64), mic.astype(np.float64)
    if x.size < MIN_S * rate or not np.any(x):
        return None
    size = next_fast_len(x.size + taps)  # the lags wanted (0 to taps - 1) do not wrap around
    spectrum = rfft(x, size)
    auto = irfft(spectrum * np.conj(spectrum), size)[:taps]
    cross = irfft(rfft(y, size) * np.conj(spectrum), size)[:taps]
    auto[0] *= 1.0 + load
    try:
        h = solve(auto, cross)
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
