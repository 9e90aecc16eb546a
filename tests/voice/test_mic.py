"""The microphone's path (services/voice/mic.py): the format a device is opened at, and audio at another rate or
with more channels mixed down and resampled to the service's 16 kHz mono.

The end-to-end tests drive the real PortAudio and ALSA through a simulated capture device: ALSA's `file` plugin over
its null device reads a FIFO in place of a sound card (defined in a `.asoundrc` under a temporary HOME, so each test's
process sees only its own device), and `Played` writes the recording into the FIFO in real time, as a sound card
would deliver it. Which formats are tried when a device refuses 16 kHz mono is tested on what PortAudio would say of
such a device (`formats_to_try`): ALSA's configuration cannot make a device without hardware refuse a rate.
"""

from __future__ import annotations

import itertools
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import resample_poly

from schemas.messages import HealthStatus, VoiceCommand
from services.runtime import ServiceContext
from services.voice import synth
from services.voice.audio import SAMPLE_RATE
from services.voice.engine import EngineError
from services.voice.mic import CHUNK_S, MicError, MicFormat, ToServiceRate, formats_to_try
from services.voice.service import VoiceSettings, check_settings
from tests.conftest import ROOT, wait_for
from tests.voice.streams import word_stream


def _portaudio() -> bool:
    try:
        import sounddevice  # noqa: F401
    except (ImportError, OSError):
        return False
    return True


needs_portaudio = pytest.mark.skipif(not _portaudio(), reason="PortAudio or sounddevice not installed "
                                                              "(apt-get install libportaudio2; pip install sounddevice)")
needs_espeak = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")


def test_mic_format_settings_are_checked() -> None:
    assert MicFormat.parse(None, None) == MicFormat() and MicFormat.parse("", " ") == MicFormat()
    assert MicFormat.parse("48000", "2") == MicFormat(48000, 2)
    for rate, channels, variable in (("48k", None, "HRI_VOICE_MIC_RATE"), ("4000", None, "HRI_VOICE_MIC_RATE"),
                                     (None, "0", "HRI_VOICE_MIC_CHANNELS"), (None, "9", "HRI_VOICE_MIC_CHANNELS")):
        with pytest.raises(MicError, match=variable):
            MicFormat.parse(rate, channels)
    with pytest.raises(EngineError, match="HRI_VOICE_MIC_RATE='44.1'"):  # the service exits 2 at start
        check_settings(VoiceSettings(source="mic", mic_rate="44.1"))


def _tone(freq: float, rate: int, seconds: float = 1.0, amplitude: float = 8000.0) -> np.ndarray:
    return amplitude * np.sin(2 * np.pi * freq * np.arange(int(rate * seconds)) / rate)


def _feed(convert: ToServiceRate, interleaved: np.ndarray, block: int) -> np.ndarray:
    """`interleaved` (int16 frames x channels) in PortAudio-sized blocks through `convert`; its chunks joined."""
    out = []
    for k in range(0, interleaved.shape[0], block):
        chunks = convert(interleaved[k : k + block].astype("<i2").tobytes())
        assert all(len(c) == int(CHUNK_S * SAMPLE_RATE) * 2 for c in chunks)  # the service's 30 ms chunks
        out += chunks
    return np.frombuffer(b"".join(out), "<i2").astype(float)


def _level_at(x: np.ndarray, freq: float) -> float:
    """The amplitude of `x` (16 kHz) at `freq`, from its spectrum."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size))) / (x.size / 4)
    return float(spec[int(round(freq * x.size / SAMPLE_RATE))])


@pytest.mark.parametrize("rate", [48000, 44100])
def test_a_device_rate_is_mixed_down_resampled_and_filtered(rate: int) -> None:
    """Two channels at the device's rate: a 1 kHz tone in the left, half of it in the right, arrives as one channel at
    16 kHz with the mean of the two (3/4 of the left); a 10 kHz tone, over 16 kHz's Nyquist, does not fold back as a
    6 kHz one (naive decimation would keep it whole)."""
    left = _tone(1000, rate) + _tone(10000, rate)
    frames = np.stack([left, 0.5 * left], axis=1)
    x = _feed(ToServiceRate(rate, 2), frames, block=int(CHUNK_S * rate))
    assert abs(x.size - SAMPLE_RATE) <= 0.05 * SAMPLE_RATE  # the same second of audio, less the resampler's delay
    steady = x[x.size // 4 : x.size // 4 + 8192]
    assert _level_at(steady, 1000) == pytest.approx(0.75 * 8000, rel=0.1)  # the mean of the channels
    assert _level_at(steady, 6000) < 0.01 * _level_at(steady, 1000)  # no alias of the 10 kHz tone


def test_the_same_sound_is_resampled_to_the_same_samples_in_every_process() -> None:
    """With soxr's own 16-bit output, the same sound came out a few LSB apart from one process to the next, and a
    quiet word on the VAD's edge was found in one run and not the next (stop 71). Resampled in float32 and rounded
    here, four processes give the same bytes."""
    code = ("import hashlib, numpy as np; from services.voice.mic import ToServiceRate; "
            "x = (np.random.default_rng(3).normal(0, 300, 48000 * 3)).astype('<i2').tobytes(); "
            "c = ToServiceRate(48000, 1); print(hashlib.sha1(b''.join(b''.join(c(x[k:k + 2880])) "
            "for k in range(0, len(x), 2880))).hexdigest())")  # 30 ms blocks, as a microphone's
    runs = {subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True,
                           timeout=60).stdout for _ in range(4)}
    assert len(runs) == 1 and len(runs.pop().strip()) == 40


def test_16k_mono_passes_through_unchanged_in_30ms_chunks() -> None:
    x = np.arange(-2000, 2000, dtype="<i2")
    out = _feed(ToServiceRate(SAMPLE_RATE, 1), x[:, None], block=333)
    assert out.size == x.size - x.size % 480 and np.array_equal(out, x[: out.size])


class _Devices:
    """What PortAudio says of a device (`sounddevice.query_devices`), as `formats_to_try` asks it."""

    PortAudioError = RuntimeError

    def __init__(self, rate: float, channels: int) -> None:
        self.info = {"default_samplerate": rate, "max_input_channels": channels}

    def query_devices(self, dev: object, kind: str) -> dict[str, float]:
        return self.info


def test_formats_tried_16k_mono_first_then_the_devices_own() -> None:
    assert formats_to_try(_Devices(48000, 2), None, MicFormat()) == [(16000, 1), (48000, 1), (48000, 2), (16000, 2)]
    assert formats_to_try(_Devices(16000, 1), None, MicFormat()) == [(16000, 1)]
    assert formats_to_try(_Devices(44100, 2), None, MicFormat(rate=48000)) == [(48000, 1)]  # asked: only that
    assert formats_to_try(_Devices(44100, 2), None, MicFormat(channels=2)) == [(16000, 2)]


def _alsa_home(tmp_path: Path) -> Path:
    """A HOME whose `.asoundrc` defines the capture device `testmic`: ALSA's file plugin over its null device, reading
    the FIFO `mic.raw` (int16, interleaved; `Played` writes it in real time) in place of a sound card, at whatever
    format it is opened with."""
    (tmp_path / ".asoundrc").write_text(f"""pcm.testmic {{
    type file
    slave.pcm {{ type null }}
    file "/dev/null"
    infile "{tmp_path / 'mic.raw'}"
    format "raw"
    hint {{ show on description "a simulated microphone: a recording through ALSA's file plugin" }}
}}
""")
    return tmp_path


class Played:
    """`frames` (int16, interleaved, `rate` Hz) written into `home/mic.raw`, a FIFO, in 30 ms pieces at the pace a
    sound card would deliver them, then silence until closed. ALSA's null device has no clock: the FIFO's blocking
    read paces it, so the simulated microphone neither floods the process nor runs dry."""

    def __init__(self, home: Path, frames: np.ndarray, rate: int) -> None:
        path = home / "mic.raw"
        os.mkfifo(path)
        self._fd = os.open(path, os.O_RDWR)  # never blocks, and keeps the FIFO open between the device's opens
        data = np.clip(np.rint(frames), -32768, 32767).astype("<i2")
        piece = int(0.03 * rate)
        self._pieces = [data[k : k + piece].tobytes() for k in range(0, len(data), piece)]
        self._silence = np.zeros((piece, data.shape[1]), "<i2").tobytes()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._play, daemon=True)

    def _play(self) -> None:
        start = time.monotonic()
        for k in itertools.count():
            if self._stop.is_set():
                return
            try:
                os.write(self._fd, self._pieces[k] if k < len(self._pieces) else self._silence)
            except OSError:
                return
            time.sleep(max(0.0, start + (k + 1) * 0.03 - time.monotonic()))

    def __enter__(self) -> Played:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self._fd)


def _stereo(pcm: bytes, rate: int) -> np.ndarray:
    """16 kHz mono speech as a two-channel recording at `rate`: the right channel at half the left's level."""
    x = np.frombuffer(pcm, "<i2").astype(float)
    g = math.gcd(rate, SAMPLE_RATE)
    y = resample_poly(x, rate // g, SAMPLE_RATE // g)
    return np.stack([y, 0.5 * y], axis=1)


@needs_portaudio
@needs_espeak
@pytest.mark.parametrize("asked", [False, True])
def test_level_hears_a_microphone_through_portaudio(tmp_path: Path, asked: bool) -> None:
    """`level --source mic:testmic`: the device opened at 16 kHz mono, or at 48 kHz with two channels when asked; the
    two words found either way, the two-channel ones at the mean of their channels' levels (2.5 dB under the left)."""
    pcm = word_stream("stop", "yes")
    peak = 20 * np.log10(np.abs(np.frombuffer(pcm, "<i2")).max() / 32768)
    home = _alsa_home(tmp_path)
    rate, frames = (48000, _stereo(pcm, 48000)) if asked else (SAMPLE_RATE, np.frombuffer(pcm, "<i2")[:, None])
    with Played(home, frames, rate):
        out = subprocess.run([sys.executable, "-m", "services.voice", "level", "--source", "mic:testmic", "--seconds",
                              "6", *(["--mic-rate", "48000", "--mic-channels", "2"] if asked else [])], cwd=ROOT,
                             capture_output=True, text=True, check=True, timeout=60, env={**os.environ, "HOME": str(home)})
    channels = 2 if asked else 1
    assert f"(opened at {rate} Hz, {channels} channel(s))" in out.stdout, out.stdout
    found = [line for line in out.stdout.splitlines() if line.startswith("  mic:testmic@")]
    assert len(found) == 2, out.stdout
    want = peak + (20 * np.log10(0.75) if asked else 0.0)
    for line in found:
        assert abs(float(line.split("peak ")[1].split(" dBFS")[0]) - want) < 1.0, line


@needs_portaudio
@needs_espeak
def test_service_hears_stop_from_a_48k_stereo_microphone(bus: ServiceContext, start_service, tmp_path: Path) -> None:
    """The voice service on the microphone source, the device at 48 kHz with two channels: "stop" is published, health
    says what the device was opened at, and SIGTERM closes the microphone and the session (exit 0)."""
    heard: list[VoiceCommand] = []
    bus.subscribe(bus.keys.voice_command, VoiceCommand, heard.append)
    home = _alsa_home(tmp_path)
    with Played(home, _stereo(word_stream("stop"), 48000), 48000):
        proc = start_service("voice", env={"HOME": str(home), "HRI_VOICE_SOURCE": "mic:testmic",
                                           "HRI_VOICE_MIC_RATE": "48000", "HRI_VOICE_MIC_CHANNELS": "2"})
        wait_for(lambda: any(h.command is not None for h in heard), timeout=60)
        assert [h.command.value for h in heard if h.command is not None] == ["stop"]
        health = wait_for(lambda: (h := bus.query_health("voice")) is not None and "mic_rate_hz" in h.detail and h,
                          timeout=10)
        assert health.status == HealthStatus.OK
        assert health.detail["mic_rate_hz"] == 48000 and health.detail["mic_channels"] == 2
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(15) == 0
    text = Path(proc.log_path).read_text()  # type: ignore[attr-defined]
    assert "microphone opened" in text and "48000" in text
