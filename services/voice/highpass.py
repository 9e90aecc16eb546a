"""A live stream's DC offset and rumble taken out before anything listens to it.

Some microphones and sound cards hand over their samples with a constant offset (a cheap USB codec, an I2S MEMS
microphone: tens to thousands of LSB). Nothing in the spotter's training or the benches had one, and it matters: on
tuning clips through a 48 kHz microphone's path (voice README, "A microphone's DC offset"), an offset of 0.03 of full
scale (-30 dBFS) left the segmenter without a segment over 304 of 480 words peaking at -38 dBFS (13 without it),
because the offset is louder than the speech in every level the segmenter keeps (its noise floor, the VAD lift's
peak). A second-order Butterworth high-pass (scipy's `butter` and `sosfilt`, its state carried from chunk to chunk)
at `hz` removes it; speech has almost nothing under 60 Hz. The segmenter switches it on only once the stream shows an
offset (`SegmenterConfig.highpass_from_dbfs`, `highpass_dc_share`): always on, it cost a few far commands on a
microphone without one. It is on by default since round voice41e, at 30 Hz (`HRI_VOICE_HIGHPASS=off` turns it off;
`python -m services.voice level` says when a microphone needs it); rounds voice41 to 41d did not pass their rules
(voice README).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import butter, sosfilt, sosfilt_zi

from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH


@dataclass
class HighPass:
    """Feed 16-bit PCM of any length (odd byte counts too); get it back filtered, as many whole samples as came."""

    hz: float
    order: int = 2
    _sos: np.ndarray = field(init=False, repr=False)
    _state: np.ndarray | None = field(default=None, init=False, repr=False)
    _odd: bytes = field(default=b"", init=False, repr=False)

    def __post_init__(self) -> None:
        if not 0.0 < self.hz < SAMPLE_RATE / 2:
            raise ValueError(f"high-pass at {self.hz} Hz: above 0 and below {SAMPLE_RATE // 2} Hz")
        self._sos = butter(self.order, self.hz, btype="highpass", fs=SAMPLE_RATE, output="sos")

    def __call__(self, pcm: bytes) -> bytes:
        data = self._odd + pcm
        n = len(data) // SAMPLE_WIDTH * SAMPLE_WIDTH
        self._odd = data[n:]
        if not n:
            return b""
        x = np.frombuffer(data[:n], "<i2").astype(np.float64)
        if self._state is None:  # as if the stream had always stood at its first sample: no step at the start
            self._state = sosfilt_zi(self._sos) * x[0]
        y, self._state = sosfilt(self._sos, x, zi=self._state)
        return np.clip(np.rint(y), -32768, 32767).astype("<i2").tobytes()
