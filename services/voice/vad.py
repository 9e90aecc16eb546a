"""Voice activity detection for the live stream: Silero VAD, a small learned model, run by onnxruntime.

Why not only WebRTC's VAD (pocketsphinx's `Endpointer`, the earlier default)? It calls most sustained
sound speech. In a stream where noise never stops - a walking robot's own servos and footfalls
(`bench/voice_walking.py`), or steady white noise 10 dB below the voice - it never leaves "speech", the
utterance runs to the 6 s cut, and the spotter refuses it as too long: no command is heard at all, "stop"
included. Silero VAD was trained on speech in many real noises; it ends the word where the voice ends.

The model is the one the openwakeword 0.4.0 wheel ships (`resources/models/silero_vad.onnx`, 1.8 MB;
openwakeword is already a dependency for the speech embedding): 30 ms frames of 16 kHz audio, an LSTM
state carried from frame to frame, one speech probability per frame, about 0.15 ms a frame on one core.

`SileroEndpointer` has the interface the `Segmenter` uses of pocketsphinx's `Endpointer`, by default with Silero's
documented thresholds: speech starts when `start_frames` (2) frames in a row reach `threshold` (0.5), and
ends after `end_frames` (5: 0.15 s, `SegmenterConfig.quiet_s`) frames in a row below `threshold - 0.15`; the
quiet frames that end it are not speech. The segmenter starts speech at 0.4 and keeps the end at 0.35 (round 18:
more words found in a walking robot's noise), and ends an utterance in a clear stream after 3 quiet frames
(`SegmenterConfig.clear_quiet_s`, round 17).

Silero's state drifts over a long stream (stop 91): a word's end is found later and later. Two options restart it,
both off by default: `reset_frames` restarts the one state outside speech (round voice50), `fresh_end_frames` keeps a
second, restarted state that ends the words it heard while the drifted one starts them (round voice50b).
"""

from __future__ import annotations

from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH
from services.voice.spotter.features import FeatureError, model_dir

FRAME_SAMPLES = 480
"""30 ms at 16 kHz, as the Endpointer's frames."""


class VadError(RuntimeError):
    """The VAD model cannot be loaded."""


def silero_model_path() -> Path:
    """The Silero VAD model inside the installed openwakeword package."""
    try:
        return model_dir(("silero_vad.onnx",)) / "silero_vad.onnx"
    except FeatureError as exc:
        raise VadError(f"{exc} (or set HRI_VOICE_VAD=webrtc)") from None


class SileroVad:
    """30 ms frames (int16 PCM bytes) -> speech probability, with the model's state carried along."""

    def __init__(self, model: Path | None = None) -> None:
        import onnxruntime as ort

        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1
        opts.inter_op_num_threads = 1
        try:
            self._session: Any = ort.InferenceSession(str(model or silero_model_path()), sess_options=opts,
                                                      providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own exception types
            raise VadError(f"cannot load the Silero VAD model: {exc}") from None
        self._sr = np.array(SAMPLE_RATE, dtype=np.int64)
        self.model = model
        self.reset()

    def reset(self) -> None:
        self._h = np.zeros((2, 1, 64), dtype=np.float32)
        self._c = np.zeros((2, 1, 64), dtype=np.float32)

    def __call__(self, frame: bytes, gain: float = 1.0) -> float:
        """The frame's speech probability; `gain` (linear) scales what the model hears, clipped at full scale."""
        x = (np.frombuffer(frame, dtype="<i2") / 32768.0).astype(np.float32)[None]
        if gain != 1.0:
            x = np.clip(x * np.float32(gain), -1.0, 1.0)
        out, self._h, self._c = self._session.run(None, {"input": x, "h": self._h, "c": self._c, "sr": self._sr})
        return float(out[0][0])


class SileroEndpointer:
    """Pocketsphinx `Endpointer`'s interface over Silero VAD: feed `frame_bytes` at a time to `process`,
    which returns speech audio (None while there is none to hand over); `speech_start` is the stream time
    (s) of the current utterance's first frame; `end_stream` hands over what is left."""

    def __init__(self, threshold: float = 0.5, start_frames: int = 2, end_frames: int = 5,
                 vad: SileroVad | None = None, end_threshold: float | None = None,
                 reset_frames: int | None = None, fresh_end_frames: int | None = None,
                 ender: SileroVad | None = None) -> None:
        self.threshold = threshold
        self.neg_threshold = threshold - 0.15 if end_threshold is None else end_threshold
        if self.neg_threshold > threshold:
            raise ValueError(f"the end threshold {self.neg_threshold} is above the start threshold {threshold}")
        self.start_frames = start_frames
        self.end_frames = end_frames
        self._vad = vad or SileroVad()
        self.frame_bytes = FRAME_SAMPLES * SAMPLE_WIDTH
        self.in_speech = False
        self.speech_start = 0.0
        self._frames = 0  # frames processed
        self._onset: list[bytes] = []  # frames at or above the threshold, before speech is declared
        self.gain = 1.0
        """What the model hears is the frame times this (the segmenter's `vad_lift_dbfs`); the audio handed over is
        the frame as it came."""
        self._quiet: list[bytes] = []  # frames below the lower threshold inside speech, held back
        self.reset_frames = reset_frames
        """After this many frames in a row outside speech (and again after as many more), the model's state starts
        again and hears those frames once more: it has then heard as much of the stream as at the start of one that
        began that long ago (`SegmenterConfig.vad_reset_s`); None: it never starts again."""
        self._outside: deque[tuple[bytes, float]] = deque(maxlen=reset_frames or 1)
        """With `reset_frames`: the frames outside speech and any onset since the last utterance, restart or start of
        the stream, and the gain each was heard with."""
        self.fresh_end_frames = fresh_end_frames
        """A second state of the model (the ender), started again after this many frames outside speech, warmed on
        them; an utterance that it heard too (a frame at or above the threshold) ends where it hears it end. The
        first state, never restarted, still starts every utterance, and ends those the ender did not hear
        (`SegmenterConfig.vad_fresh_end_s`). None: one state."""
        self._ender = None if fresh_end_frames is None else ender or SileroVad(getattr(self._vad, "model", None))
        self._ender_outside: deque[tuple[bytes, float]] = deque(maxlen=fresh_end_frames or 1)
        """With `fresh_end_frames`: the frames outside speech (onsets included) since the ender last started again,
        the last utterance or the start of the stream, and the gain each was heard with."""
        self._ender_onset = False  # the ender heard a frame of the onset at or above the threshold
        self._ender_heard = False  # the ender heard the current utterance
        self.ender_trusted = True
        """Whether the ender may end the current utterance (set before each frame by the segmenter when
        `SegmenterConfig.vad_fresh_end_snr_db` asks for a clear utterance); False: the first state ends it."""
        self._p = 0.0  # the first state's last probability
        self._rearm = False
        """The ender ended the last utterance while the first state still heard speech: until that state hears the
        end too, the ender starts utterances (else the first state's stale speech would start one at once)."""

    def process(self, frame: bytes) -> bytes | None:
        if len(frame) != self.frame_bytes:
            raise ValueError(f"frames of {self.frame_bytes} bytes, not {len(frame)}")
        self._p = p = self._vad(frame, self.gain)
        q = p if self._ender is None else self._ender(frame, self.gain)
        self._frames += 1
        if not self.in_speech:
            self._rearm = self._rearm and p >= self.neg_threshold
            self._onset = [*self._onset, frame] if (q if self._rearm else p) >= self.threshold else []
            self._ender_onset = bool(self._onset) and (self._ender_onset or q >= self.threshold)
            if self._ender is not None:
                self._ender_outside.append((frame, self.gain))
                if len(self._ender_outside) == self.fresh_end_frames and not self._onset:
                    _warm(self._ender, self._ender_outside)
            if not self._onset and self.reset_frames is not None:
                self._outside.append((frame, self.gain))
                if len(self._outside) == self.reset_frames:
                    _warm(self._vad, self._outside)
            if len(self._onset) < self.start_frames:
                return None
            self.in_speech = True
            self._outside.clear()
            self._ender_heard, self._ender_onset = self._ender_onset, False
            self.speech_start = (self._frames - len(self._onset)) * FRAME_SAMPLES / SAMPLE_RATE
            out, self._onset, self._quiet = b"".join(self._onset), [], []
            return out
        self._ender_heard = self._ender_heard or q >= self.threshold
        if (q if self._ender_ends else p) >= self.neg_threshold:
            out, self._quiet = b"".join([*self._quiet, frame]), []
            return out
        self._quiet.append(frame)
        if len(self._quiet) < self.end_frames:
            return None
        self._ended()
        return b""  # the utterance ended; its quiet tail is not speech

    def forget(self) -> None:
        """Outside speech: the model's state starts again, as at the start of a stream. The segmenter calls it when
        what the model heard so far no longer stands for the stream (its high-pass switched on for a DC offset:
        after half a second of the offset Silero found more words, far words and other words alike, for a second
        or more; voice README, round voice41c)."""
        if self.in_speech:
            raise RuntimeError("the VAD's state is forgotten only outside speech")
        self._vad.reset()
        self._onset = []
        self._outside.clear()
        if self._ender is not None:
            self._ender.reset()
            self._ender_outside.clear()

    def _ended(self) -> None:
        """The current utterance ended (its quiet frames, or `end_now`)."""
        self.in_speech, self._quiet, self._onset = False, [], []
        self._ender_outside.clear()
        self._rearm = self._ender is not None and self._ender_ends and self._p >= self.neg_threshold

    @property
    def _ender_ends(self) -> bool:
        """The ender, not the first state, ends the current utterance."""
        return self._ender_heard and self.ender_trusted

    @property
    def quiet_frames(self) -> int:
        """Quiet frames in a row so far inside the current utterance (held back: not yet handed over)."""
        return len(self._quiet) if self.in_speech else 0

    def end_now(self) -> None:
        """End the current utterance here, as if its quiet frames had reached `end_frames` (the segmenter's
        early look took it); the next frames at or above the threshold start a new one."""
        self._ended()

    def end_stream(self, tail: bytes) -> bytes | None:
        """The stream ended (with `tail`, less than a frame): the utterance in progress, if any, ends too."""
        if not self.in_speech:
            return None
        self.in_speech, self._quiet = False, []
        return tail


def _warm(model: SileroVad, frames: deque[tuple[bytes, float]]) -> None:
    """`model`'s state starts again and hears `frames` (each with its gain), which are then counted afresh."""
    model.reset()
    for frame, gain in frames:
        model(frame, gain)
    frames.clear()
