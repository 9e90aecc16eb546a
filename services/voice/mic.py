"""A microphone through PortAudio (`sounddevice`), delivered as the service's audio: 16 kHz, 16-bit mono PCM in
30 ms chunks.

Many capture devices cannot open at 16 kHz mono: a USB microphone or a laptop's codec opened directly (ALSA `hw:`)
often offers only 44.1 or 48 kHz, or only two channels. The microphone is opened at 16 kHz mono when it can be.
When PortAudio refuses that, it is opened at the device's own rate (PortAudio's `default_samplerate`), with one
channel or else two, and the service mixes the channels down and resamples to 16 kHz itself (`soxr`, a streaming
resampler of the SoX library's quality). `HRI_VOICE_MIC_RATE` and `HRI_VOICE_MIC_CHANNELS` ask for a format outright,
for a device whose own resampling is poor or which misreports what it can do.
"""

from __future__ import annotations

import queue
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH, rounded_pcm

CHUNK_S = 0.03
ALTERNATIVES = "mic, mic:<device>, a WAV file, a folder of WAV files, watch:<dir>, stdin"
MAX_CHANNELS = 8

Stop = Callable[[], bool]
"""Returns True when the source should stop."""


class MicError(RuntimeError):
    """A microphone that cannot be opened or stopped delivering audio; the message names it and the alternatives."""


@dataclass(frozen=True)
class MicFormat:
    """What the device is opened at; None: the service's own (16 kHz, mono), or what the device offers."""

    rate: int | None = None
    channels: int | None = None

    @classmethod
    def parse(cls, rate: str | None, channels: str | None) -> MicFormat:
        """`HRI_VOICE_MIC_RATE` (Hz, 8000 to 192000) and `HRI_VOICE_MIC_CHANNELS` (1 to 8); `MicError` names the
        variable otherwise."""
        return cls(_int_in("HRI_VOICE_MIC_RATE", rate, 8000, 192000, "Hz, e.g. 48000"),
                   _int_in("HRI_VOICE_MIC_CHANNELS", channels, 1, MAX_CHANNELS, "channels, mixed down to one"))


def _int_in(variable: str, raw: str | None, low: int, high: int, what: str) -> int | None:
    if raw is None or not raw.strip():
        return None
    try:
        value = int(raw)
    except ValueError:
        value = low - 1
    if not low <= value <= high:
        raise MicError(f"{variable}={raw!r}: {what}, from {low} to {high}")
    return value


class ToServiceRate:
    """Interleaved 16-bit PCM at `rate` Hz with `channels` channels -> 16 kHz mono PCM in `CHUNK_S` chunks: the
    channels averaged, then resampled by a streaming `soxr` resampler (its state carried across chunks; in float32,
    so that the same sound always gives the same samples)."""

    def __init__(self, rate: int, channels: int) -> None:
        self.rate, self.channels = rate, channels
        self._resampler: Any = None
        if rate != SAMPLE_RATE:
            try:
                import soxr  # lazily: only a microphone that cannot give 16 kHz needs it
            except ImportError as exc:
                raise MicError(f"the microphone gives {rate} Hz and resampling needs soxr ({exc}): "
                               f"pip install soxr, or the project's mic extra") from None
            # in float32, rounded back to 16-bit here: with soxr's own 16-bit output the same sound came out a few
            # LSB apart from one process to the next (stop 71), and quiet speech on the VAD's edge was found in one
            # run and not the next
            self._resampler = soxr.ResampleStream(rate, SAMPLE_RATE, 1, dtype="float32")
        self._out = b""
        self._step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH

    def __call__(self, data: bytes) -> list[bytes]:
        x = np.frombuffer(data, "<i2")
        if self.channels > 1:
            x = x[: x.size - x.size % self.channels].reshape(-1, self.channels).astype(np.int32).mean(axis=1)
            x = np.rint(x).astype(np.int16)
        if self._resampler is not None:
            y = self._resampler.resample_chunk(x.astype(np.float32) / np.float32(32768.0))
            x = np.frombuffer(rounded_pcm(y), "<i2")
        self._out += np.asarray(x, "<i2").tobytes()
        cut = len(self._out) - len(self._out) % self._step
        out = [self._out[i : i + self._step] for i in range(0, cut, self._step)]
        self._out = self._out[cut:]
        return out


def formats_to_try(sd: Any, dev: int | str | None, asked: MicFormat) -> list[tuple[int, int]]:
    """The (rate, channels) to try, in order: what was asked, or 16 kHz mono and then the device's own rate with one
    channel or two."""
    if asked.rate is not None or asked.channels is not None:
        return [(asked.rate or SAMPLE_RATE, asked.channels or 1)]
    tries = [(SAMPLE_RATE, 1)]
    try:
        info = sd.query_devices(dev, "input")
    except (sd.PortAudioError, ValueError):
        return tries  # opening it says what is wrong
    own = int(info["default_samplerate"])
    for channels in (1, 2):
        if channels <= int(info["max_input_channels"]) and (own, channels) not in tries:
            tries.append((own, channels))
    if (SAMPLE_RATE, 2) not in tries and int(info["max_input_channels"]) >= 2:
        tries.append((SAMPLE_RATE, 2))
    return tries


def mic_chunks(device: str, stop: Stop, asked: MicFormat | None = None,
               opened: Callable[[int, int], None] | None = None) -> Iterator[bytes]:
    """16 kHz mono PCM from a PortAudio input, in `CHUNK_S` chunks, until `stop()`; `MicError` names the problem and
    the alternatives. `opened(rate, channels)` is told the format the device was opened at."""
    try:
        import sounddevice as sd  # lazily: needs the system PortAudio library
    except (ImportError, OSError) as exc:
        raise MicError(f"microphone unavailable: {exc} (install PortAudio: apt-get install "
                       f"libportaudio2; or use another source: {ALTERNATIVES})") from None
    dev: int | str | None = int(device) if device.isdigit() else (device or None)
    chunks: queue.Queue[bytes] = queue.Queue(maxsize=200)

    def callback(indata: bytes, frames: int, t: object, status: object) -> None:
        try:
            chunks.put_nowait(bytes(indata))
        except queue.Full:  # the decoder fell behind: drop the newest audio rather than block PortAudio
            pass

    refused: list[str] = []
    stream = None
    for rate, channels in formats_to_try(sd, dev, asked or MicFormat()):
        try:
            stream = sd.RawInputStream(samplerate=rate, channels=channels, dtype="int16", device=dev,
                                       blocksize=int(CHUNK_S * rate), callback=callback)
        except (sd.PortAudioError, ValueError) as exc:  # no such device, no input channels, a format it lacks
            refused.append(f"{rate} Hz x{channels}: {exc}")
            continue
        try:
            stream.start()
            break
        except sd.PortAudioError as exc:  # opened but would not start: closed before the next format is tried
            stream.close()
            refused.append(f"{rate} Hz x{channels}: {exc}")
            stream = None
    if stream is None:
        raise MicError(f"microphone {device or 'default'!r} cannot be opened ({'; '.join(refused)}); set "
                       f"HRI_VOICE_MIC_RATE / HRI_VOICE_MIC_CHANNELS to a format it has, or use another source: "
                       f"{ALTERNATIVES}")
    try:
        convert = ToServiceRate(rate, channels)
        if opened is not None:
            opened(rate, channels)
        while not stop():
            try:
                data = chunks.get(timeout=0.2)
            except queue.Empty:
                if not stream.active:
                    raise MicError(f"microphone {device or 'default'!r} stopped delivering audio") from None
                continue
            yield from convert(data)
    finally:
        stream.stop()
        stream.close()
