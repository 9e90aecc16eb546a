"""Where utterances come from: a microphone, WAV file(s), a spool folder, or raw PCM on stdin.

Every source yields `Utterance`s of 16 kHz, 16-bit, mono PCM. Streams (microphone, stdin, long
WAV files) are cut into utterances by the VAD `Segmenter`; a short WAV file is one utterance.

Source specs (`HRI_VOICE_SOURCE`):

- `mic` or `mic:<device>`: a sounddevice input (PortAudio), device by index or name, at 16 kHz mono or else at
  the device's own rate and channels, resampled (`mic.py`; `HRI_VOICE_MIC_RATE`, `HRI_VOICE_MIC_CHANNELS`).
- `<file>.wav`: one WAV file; `<dir>`: every `*.wav` in it, by name.
- `watch:<dir>`: a spool folder. WAVs already there are decoded first (oldest first), then each
  new one as it appears (polled every 50 ms). Names ending in `.tmp` are ignored: writers should
  write `x.wav.tmp` and rename it to `x.wav`. A file whose header does not yet cover its data is
  retried until its size has been stable for 0.5 s. Consumed files are left in place (remembered
  by name, size and mtime) unless `consume="delete"`.
- `stdin`: raw 16 kHz, 16-bit little-endian mono PCM on standard input.
"""

from __future__ import annotations

import io
import os
import select
import sys
import time
import wave
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, Literal, Protocol

from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH, AudioError, duration_s, read_wav
from services.voice.clock import StreamClock
from services.voice.engine import Recognition
from services.voice.level import Meter, amplified, amplify
from services.voice.mic import ALTERNATIVES, CHUNK_S, MicError, MicFormat, Stop, mic_chunks
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig


class SourceError(RuntimeError):
    """A source that cannot be opened (missing device, PortAudio, file or folder)."""


@dataclass(frozen=True)
class Utterance:
    pcm: bytes
    origin: str
    """File name, or `<source>@<offset>s` for streams."""
    stamp: float = field(default_factory=time.time)
    """UNIX time the utterance was captured (stream: when its speech ended; file: when it was found)."""
    recognition: Recognition | None = None
    """Already decoded: the segmenter's early look took this utterance (`Segment.recognition`)."""
    snr_db: float | None = None
    """Streams with Silero: the speech level over the noise floor before it (`Segment.snr_db`)."""
    start_s: float | None = None
    """Streams: where the utterance starts, seconds from the stream's start (`Segment.start_s`)."""
    began: float | None = None
    """Live streams: when its audio began (UNIX seconds, `clock.StreamClock`), however long it waited to be read and
    the segmenter held it; recordings read faster than they play have no meaningful one."""

    @property
    def seconds(self) -> float:
        return duration_s(self.pcm)


@dataclass(frozen=True)
class SourceSpec:
    kind: Literal["mic", "file", "folder", "watch", "stdin"]
    target: str = ""

    @classmethod
    def parse(cls, spec: str) -> SourceSpec:
        spec = spec.strip()
        if spec == "mic":
            return cls("mic")
        if spec.startswith("mic:"):
            return cls("mic", spec[4:])
        if spec == "stdin":
            return cls("stdin")
        if spec.startswith("watch:"):
            if not spec[6:]:
                raise SourceError(f"watch: needs a folder, e.g. watch:/tmp/spool (sources: {ALTERNATIVES})")
            return cls("watch", spec[6:])
        if not spec:
            raise SourceError(f"empty voice source; use one of: {ALTERNATIVES}")
        path = Path(spec)
        if path.is_dir():
            return cls("folder", spec)
        if path.suffix.lower() == ".wav" or path.exists():
            return cls("file", spec)
        raise SourceError(f"{spec!r} is neither a WAV file nor a folder; sources: {ALTERNATIVES}")

    def __str__(self) -> str:
        return {"mic": f"mic:{self.target}" if self.target else "mic", "stdin": "stdin",
                "watch": f"watch:{self.target}"}.get(self.kind, self.target)


Recognise = Callable[[bytes], Recognition]
"""The engine's decoder, for the segmenter's early look."""


HighpassState = Callable[[bool, float], None]
"""Told whether a live stream is heard through the high-pass, and the offset that switched it on (full scale 1.0)."""


class Echo(Protocol):
    """The echo canceller as a live stream uses it (`echo.EchoCanceller`)."""

    def __call__(self, chunk: bytes, captured: float | None) -> bytes:
        """A live stream's chunk and when its first sample was captured (wall clock; None until known, and at the
        stream's end) -> the chunk with the robot's own voice cancelled, with what it held back before it."""
        ...

    @property
    def robot_near(self) -> bool:
        """Whether the robot's voice may lie in what the last call passed on (`SegmenterConfig.floor_hold`)."""
        ...


def stream_utterances(
    chunks: Iterator[bytes], origin: str, config: SegmenterConfig | None = None, recognise: Recognise | None = None,
    on_highpass: HighpassState | None = None, echo: Echo | None = None,
) -> Iterator[Utterance]:
    """VAD-cut a stream of PCM chunks into utterances (with `recognise`, the segmenter's early look is on).
    `on_highpass` is told the high-pass's state as the stream starts and again if a DC offset switches it on
    (`SegmenterConfig.highpass_from_dbfs`). `echo` (`echo.EchoCanceller`) takes each chunk, with when it was captured,
    before the segmenter does, and says where the robot's voice lies (`SegmenterConfig.floor_hold`)."""
    seg = Segmenter(config or SegmenterConfig(), recognise=recognise)
    highpass_on = seg.highpass_on
    if on_highpass is not None:
        on_highpass(highpass_on, 0.0)
    heard_s, clock = 0.0, StreamClock()

    def utterances(segments: list[Segment]) -> Iterator[Utterance]:
        for s in segments:
            yield Utterance(s.pcm, f"{origin}@{s.start_s:.2f}s", recognition=s.recognition, snr_db=s.snr_db,
                            start_s=s.start_s, began=clock.wall(s.start_s))

    for chunk in chunks:
        seconds = len(chunk) / (SAMPLE_RATE * SAMPLE_WIDTH)
        heard_s += seconds
        clock.heard(heard_s)
        robot = False
        if echo is not None:
            chunk = echo(chunk, clock.wall(heard_s - seconds))
            robot = echo.robot_near
        yield from utterances(seg.feed(chunk, robot))
        if on_highpass is not None and seg.highpass_on and not highpass_on:
            highpass_on = True
            on_highpass(True, seg.offset_seen_so_far()[1])
    if echo is not None:  # what the canceller still holds back, as heard
        yield from utterances(seg.feed(echo(b"", None)))
    yield from utterances(seg.flush())


TRIM_CONFIG = SegmenterConfig(vad="webrtc", window_s=0.3, ratio=0.9, highpass_hz=None)
"""Trimming a file is not latency-bound: a longer VAD window; WebRTC's VAD and no high-pass, as the spotter's
training clips were trimmed (its held-out figures are measured on clips trimmed so)."""


def trim_to_speech(pcm: bytes, config: SegmenterConfig | None = None) -> bytes:
    """The span of a short recording from the VAD's first speech to its last (with pre- and post-roll);
    the whole recording if the VAD finds none. Long silences around a word hurt decoding."""
    seg = Segmenter(config or TRIM_CONFIG)
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    found = [s for i in range(0, len(pcm), step) for s in seg.feed(pcm[i : i + step])] + seg.flush()
    if not found:
        return pcm
    rate = SAMPLE_RATE * SAMPLE_WIDTH
    start = max(0, int(found[0].start_s * SAMPLE_RATE) * SAMPLE_WIDTH)
    end = min(len(pcm), int(found[-1].end_s * SAMPLE_RATE) * SAMPLE_WIDTH)
    return pcm[start:end] if end - start >= 0.1 * rate else pcm


def file_utterances(path: Path, *, max_whole_s: float = 5.0, gain_db: float = 0.0) -> Iterator[Utterance]:
    """A short WAV is one utterance (trimmed to its speech); a longer one is a recording cut by the VAD. `gain_db`:
    the input gain (`level.amplify`)."""
    pcm = amplify(read_wav(path), gain_db)
    if duration_s(pcm) <= max_whole_s:
        yield Utterance(trim_to_speech(pcm), path.name)
        return
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    yield from stream_utterances((pcm[i : i + step] for i in range(0, len(pcm), step)), path.name)


def folder_files(folder: Path) -> list[Path]:
    if not folder.is_dir():
        raise SourceError(f"{folder}: no such folder (sources: {ALTERNATIVES})")
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() == ".wav")


def _complete(path: Path) -> bool:
    """True when the WAV header's data length is all there (so a half-written file waits)."""
    try:
        with wave.open(str(path), "rb") as w:
            want = w.getnframes() * w.getsampwidth() * w.getnchannels()
            return want > 0 and len(w.readframes(w.getnframes())) >= want
    except (wave.Error, EOFError, OSError):
        return False


@dataclass
class SpoolWatcher:
    """Finds new complete WAV files in a folder, oldest first."""

    folder: Path
    consume: Literal["keep", "delete"] = "keep"
    settle_s: float = 0.5
    _seen: set[tuple[str, int, int]] = field(default_factory=set)
    _sizes: dict[str, tuple[int, float]] = field(default_factory=dict)

    def ready(self) -> list[Path]:
        if not self.folder.is_dir():
            raise SourceError(f"spool folder {self.folder} does not exist (sources: {ALTERNATIVES})")
        found: list[tuple[int, str, Path]] = []
        now = time.monotonic()
        for entry in os.scandir(self.folder):
            if not entry.is_file() or entry.name.endswith(".tmp") or not entry.name.lower().endswith(".wav"):
                continue
            st = entry.stat()
            key = (entry.name, st.st_size, st.st_mtime_ns)
            if key in self._seen:
                continue
            path = Path(entry.path)
            if not _complete(path):
                size, since = self._sizes.get(entry.name, (-1, now))
                if size != st.st_size:
                    self._sizes[entry.name] = (st.st_size, now)
                    continue
                if now - since < self.settle_s:
                    continue
            self._sizes.pop(entry.name, None)
            found.append((st.st_mtime_ns, entry.name, path))
        return [p for _, _, p in sorted(found)]

    def done(self, path: Path) -> None:
        try:
            st = path.stat()
        except OSError:
            return
        self._seen.add((path.name, st.st_size, st.st_mtime_ns))
        if self.consume == "delete":
            path.unlink(missing_ok=True)


def watch_utterances(
    folder: Path, stop: Stop, *, poll_s: float = 0.05, consume: Literal["keep", "delete"] = "keep",
    on_error: Callable[[Path, AudioError], None] | None = None, gain_db: float = 0.0,
) -> Iterator[Utterance]:
    watcher = SpoolWatcher(folder, consume)
    while not stop():
        for path in watcher.ready():
            found = time.time()
            try:
                for utt in file_utterances(path, gain_db=gain_db):
                    yield Utterance(utt.pcm, utt.origin, found)
            except AudioError as exc:
                if on_error is not None:
                    on_error(path, exc)
            finally:
                watcher.done(path)
        time.sleep(poll_s)


def stdin_chunks(stream: BinaryIO, stop: Stop, poll_s: float = 0.2) -> Iterator[bytes]:
    """Chunks of a byte stream until EOF or `stop()`. A real file descriptor is polled with `select`
    so that a silent pipe never blocks shutdown."""
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    try:
        fd: int | None = stream.fileno()
    except (AttributeError, OSError, io.UnsupportedOperation):
        fd = None
    while not stop():
        if fd is None:
            data = stream.read(step)
        else:
            ready, _, _ = select.select([fd], [], [], poll_s)
            if not ready:
                continue
            data = os.read(fd, step)
        if not data:
            return
        yield data


def microphone(device: str, stop: Stop, asked: MicFormat | None = None,
               opened: Callable[[int, int], None] | None = None) -> Iterator[bytes]:
    """`mic.mic_chunks`, its errors as `SourceError`s."""
    try:
        yield from mic_chunks(device, stop, asked, opened)
    except MicError as exc:
        raise SourceError(str(exc)) from None


def utterances(
    spec: SourceSpec, stop: Stop, *, stdin: BinaryIO | None = None,
    on_error: Callable[[Path, AudioError], None] | None = None,
    segmenter: SegmenterConfig | None = None, recognise: Recognise | None = None,
    gain_db: float = 0.0, meter: Meter | None = None, mic: MicFormat | None = None,
    mic_opened: Callable[[int, int], None] | None = None, on_highpass: HighpassState | None = None,
    echo: Echo | None = None,
) -> Iterator[Utterance]:
    """All utterances of one source until it ends or `stop()`; raises `SourceError` if it cannot open.
    `recognise` turns on the segmenter's early look for live streams (microphone, stdin); files and spools
    are not latency-bound and are decoded whole. `gain_db`: the input gain (`level.amplify`), before the VAD;
    `meter`: fed a live stream's chunks after the gain (`level.Meter`); `mic`: the format to open a microphone at
    (default: 16 kHz mono, or what the device offers), and `mic_opened(rate, channels)` is told what it opened at;
    `on_highpass`: a live stream's high-pass state, `echo`: its echo canceller (`stream_utterances`)."""
    if spec.kind in ("mic", "stdin"):
        chunks = (microphone(spec.target, stop, mic, mic_opened) if spec.kind == "mic"
                  else stdin_chunks(stdin or sys.stdin.buffer, stop))
        chunks = amplified(chunks, gain_db)
        if meter is not None:
            chunks = meter.metered(chunks)
        yield from stream_utterances(chunks, str(spec), segmenter, recognise, on_highpass, echo)
    elif spec.kind == "file":
        path = Path(spec.target)
        if not path.is_file():
            raise SourceError(f"{path}: no such WAV file (sources: {ALTERNATIVES})")
        yield from file_utterances(path, gain_db=gain_db)
    elif spec.kind == "folder":
        for path in folder_files(Path(spec.target)):
            if stop():
                return
            try:
                yield from file_utterances(path, gain_db=gain_db)
            except AudioError as exc:
                if on_error is None:
                    raise
                on_error(path, exc)
    else:
        yield from watch_utterances(Path(spec.target), stop, on_error=on_error, gain_db=gain_db)

