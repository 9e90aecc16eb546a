"""The input's level: `HRI_VOICE_GAIN` before the VAD, the meter in health, and advice when speech is too quiet for
the VAD or clipped (services/voice/level.py; figures from bench/voice_levels.py in the voice README)."""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from schemas.messages import VoiceCommand
from services.runtime import ServiceContext
from services.voice import synth
from services.voice.audio import from_pcm, to_pcm
from services.voice.level import (
    FULL_SCALE,
    NOISY_SNR_DB,
    QUIET_PEAK_DBFS,
    Level,
    LevelError,
    Meter,
    amplify,
    gain_from,
)
from services.voice.segmenter import SegmenterConfig
from services.voice.sources import SourceSpec, utterances
from tests.conftest import ROOT, service_env, wait_for
from tests.voice.streams import word_stream

HISS_DBFS = -70.0


def at_peak(pcm: bytes, peak_dbfs: float, seed: int = 2) -> bytes:
    """The stream scaled so that its loudest sample is at `peak_dbfs`, in a quiet room's hiss (-70 dBFS RMS)."""
    x = from_pcm(pcm)
    y = x * (10 ** (peak_dbfs / 20) / np.abs(x).max())
    return to_pcm(y + np.random.default_rng(seed).normal(0, 10 ** (HISS_DBFS / 20), y.size))


def test_gain_setting_is_checked() -> None:
    assert gain_from(None) == 0.0 and gain_from("") == 0.0 and gain_from(" ") == 0.0
    assert gain_from("12") == 12.0 and gain_from("40") == 40.0 and gain_from(0) == 0.0
    for bad in ("-6", "41", "loud", "nan", "inf"):
        with pytest.raises(LevelError, match="HRI_VOICE_GAIN"):
            gain_from(bad)


def test_gain_amplifies_and_clips_at_full_scale_as_a_sound_card() -> None:
    pcm = np.array([0, 100, -100, 20000, -20000], "<i2").tobytes()
    assert amplify(pcm, 0.0) == pcm
    out = np.frombuffer(amplify(pcm, 20 * np.log10(2)), "<i2")
    assert out.tolist() == [0, 200, -200, 32767, -32768]


def test_level_of_an_utterance_and_its_advice() -> None:
    quiet = Level.of(np.array([0, 300, -500], "<i2").tobytes())  # -36.3 dBFS
    assert quiet.is_quiet and not quiet.is_clipped
    assert round(quiet.peak_dbfs, 1) == -36.3
    advice = quiet.advice(gain_db=0.0)
    assert advice is not None and "HRI_VOICE_GAIN=17" in advice  # to -20 dBFS, inside the training clips' range
    assert "HRI_VOICE_GAIN=23" in (quiet.advice(gain_db=6.0) or "")  # on top of the gain already set
    clipped = Level.of(np.array([FULL_SCALE] * 5 + [0] * 995, "<i2").tobytes())
    assert clipped.is_clipped and clipped.clipped == 5
    assert "alsamixer" in (clipped.advice(0.0) or "")  # only the microphone's own gain mends it
    assert "lower HRI_VOICE_GAIN (now 12)" in (clipped.advice(12.0) or "")
    one = Level.of(np.array([FULL_SCALE] + [1000] * 1999, "<i2").tobytes())  # one sample at full scale: a click
    assert not one.is_clipped and not one.is_quiet and one.advice() is None and one.kind is None


def test_speech_near_the_noise_floor_is_told_to_come_nearer_not_to_raise_the_gain() -> None:
    """Under `NOISY_SNR_DB` over the floor the spotter takes more words for commands (round voice38): gain cannot
    mend that, a nearer microphone can. A file has no floor, so no such judgement."""
    pcm = np.array([0, 3000, -3000], "<i2").tobytes()  # -21 dBFS: loud enough
    noisy = Level.of(pcm, snr_db=NOISY_SNR_DB - 4)
    assert noisy.is_noisy and noisy.kind == "noisy"
    advice = noisy.advice(0.0) or ""
    assert "16 dB over the noise floor" in advice and "nearer" in advice and "HRI_VOICE_GAIN" not in advice
    assert Level.of(pcm, snr_db=NOISY_SNR_DB + 1).advice() is None and Level.of(pcm).advice() is None
    both = Level.of(np.array([0, 300], "<i2").tobytes(), snr_db=10.0)  # quiet and noisy: the VAD's gain, then distance
    assert both.kind == "quiet" and "HRI_VOICE_GAIN=" in (both.advice() or "") and "nearer" in (both.advice() or "")
    clipped = Level.of(np.array([FULL_SCALE] * 5 + [0] * 995, "<i2").tobytes(), snr_db=5.0)
    assert clipped.kind == "clipped" and "nearer" not in (clipped.advice() or "")  # the worst first
    meter = Meter()
    meter.utterance(pcm, 12.0)
    meter.utterance(pcm, 30.0)
    meter.utterance(pcm)
    assert meter.detail()["noisy_utterances"] == 1


def test_meter_reports_the_window_peak_and_floor() -> None:
    reports: list[dict[str, object]] = []
    meter = Meter(window_s=0.3, report=reports.append, report_s=0.09)
    loud = np.tile(np.array([16384, -16384], "<i2"), 240).tobytes()  # -6 dBFS
    hiss = np.tile(np.array([33, -33], "<i2"), 240).tobytes()  # about -60 dBFS
    meter.feed(loud)
    for _ in range(9):
        meter.feed(hiss)
    d = meter.detail()
    assert d["input_peak_dbfs"] == -6.0 and round(float(d["input_floor_dbfs"])) == -60  # type: ignore[arg-type]
    meter.feed(hiss)  # the loud chunk leaves the 0.3 s window
    assert meter.detail()["input_peak_dbfs"] == round(20 * np.log10(33 / 32768), 1)
    assert len(reports) == 3  # every 0.09 s of audio: 11 chunks fed
    meter.utterance(np.array([300], "<i2").tobytes())
    assert meter.detail()["quiet_utterances"] == 1 and meter.detail()["last_peak_dbfs"] == -40.8


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_gain_lets_the_vad_find_speech_too_quiet_for_it() -> None:
    """Two words peaking at -46 dBFS: Silero, hearing the stream as it came (the lift off), finds neither; with 20 dB
    of gain, both. The default's second VAD hears the stream lifted by at most 15 dB here (the noise floor, -70 dBFS,
    is kept under -55): one of them without gain; at -42 dBFS, where the first finds one, both, as they came."""
    pcm = at_peak(word_stream("stop", "yes"), -46.0)
    one_vad = replace(SegmenterConfig(), vad_lift_dbfs=None)
    found = [list(utterances(SourceSpec("stdin"), lambda: False, stdin=io.BytesIO(pcm), gain_db=g, segmenter=one_vad))
             for g in (0.0, 20.0)]
    assert len(found[0]) == 0
    assert len(found[1]) == 2
    assert all(QUIET_PEAK_DBFS < Level.of(u.pcm).peak_dbfs < -20 for u in found[1])  # now within the trained levels
    assert len(list(utterances(SourceSpec("stdin"), lambda: False, stdin=io.BytesIO(pcm)))) == 1
    nearer = at_peak(word_stream("stop", "yes"), -42.0)
    assert len(list(utterances(SourceSpec("stdin"), lambda: False, stdin=io.BytesIO(nearer), segmenter=one_vad))) == 1
    lifted = list(utterances(SourceSpec("stdin"), lambda: False, stdin=io.BytesIO(nearer)))
    assert len(lifted) == 2 and all(-44.0 < Level.of(u.pcm).peak_dbfs < QUIET_PEAK_DBFS for u in lifted)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_service_applies_the_gain_and_warns_when_it_clips(bus: ServiceContext, router_endpoint: str, robot_id: str,
                                                         tmp_path: Path) -> None:
    """A quiet "stop" heard only thanks to HRI_VOICE_GAIN=20, then a word the gain drives past full scale: counted as
    clipped in health, and the log says to lower HRI_VOICE_GAIN."""
    heard: list[VoiceCommand] = []
    bus.subscribe(bus.keys.voice_command, VoiceCommand, heard.append)
    quiet = at_peak(word_stream("stop"), -46.0)
    loud = at_peak(word_stream("yes"), -6.0)  # +20 dB: 14 dB past full scale
    log_path = tmp_path / "voice.log"
    with open(log_path, "wb") as log:
        proc = subprocess.Popen([sys.executable, "-m", "services.voice"], cwd=ROOT, stdin=subprocess.PIPE, stdout=log,
                                stderr=subprocess.STDOUT,
                                env=service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_VOICE_GAIN="20"))
        try:
            assert proc.stdin is not None
            proc.stdin.write(quiet + loud)
            proc.stdin.flush()
            wait_for(lambda: len(heard) >= 2, timeout=30)
            assert heard[0].command is not None and heard[0].command.value == "stop"
            health = wait_for(lambda: (h := bus.query_health("voice")) is not None and h.detail.get("utterances") == 2
                              and h, timeout=5)
            assert health.detail["gain_db"] == 20.0
            assert health.detail["clipped_utterances"] == 1 and health.detail["quiet_utterances"] == 0
            assert health.detail["noisy_utterances"] == 1  # the far "stop": 20 dB of gain raised its hiss too
            assert health.detail["input_peak_dbfs"] == 0.0  # full scale within the last 10 s
            assert health.detail["input_floor_dbfs"] < -40  # the hiss, 20 dB up
            proc.send_signal(signal.SIGTERM)
            assert proc.wait(15) == 0
        finally:
            if proc.poll() is None:
                proc.kill()
    text = log_path.read_text()
    assert "input level" in text and "lower HRI_VOICE_GAIN (now 20)" in text and "nearer the person" in text
    assert "peak_dbfs" in text


def test_a_negative_gain_exits_2_naming_the_variable() -> None:
    out = subprocess.run([sys.executable, "-m", "services.voice"], cwd=ROOT, capture_output=True, text=True,
                         check=False, timeout=60, env={**os.environ, "HRI_VOICE_GAIN": "-6", "HRI_VOICE_SOURCE": "stdin"})
    assert out.returncode == 2
    assert "HRI_VOICE_GAIN='-6'" in out.stderr and "alsamixer" in out.stderr


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_level_command_says_what_gain_a_quiet_microphone_needs() -> None:
    """`python -m services.voice level`: words too quiet for the VAD are found nowhere, and the advice's gain finds
    them at a level the spotter was trained on; but they are as near the room's hiss as before, so the verdict then
    asks for a nearer microphone. The same words said nearer (-20 dBFS in the same hiss) are fine."""
    quiet = at_peak(word_stream("stop", "yes"), -46.0)

    def check(pcm: bytes, *args: str) -> list[str]:
        out = subprocess.run([sys.executable, "-m", "services.voice", "level", "--source", "stdin", *args], cwd=ROOT,
                             input=pcm, capture_output=True, check=True, timeout=60)
        return out.stdout.decode().strip().splitlines()

    lines = check(quiet, "--vad-lift", "off")  # one VAD, hearing the stream as it came
    assert "0 utterance(s)" in lines[-2] and "no speech found" in lines[-1]
    gain = lines[-1].rsplit("HRI_VOICE_GAIN=", 1)[1]
    lifted = check(quiet)  # the default's second VAD finds a word, and says it is quiet and near the noise
    assert "1 utterance(s)" in lifted[-2] and "(quiet)" in lifted[0]
    assert "HRI_VOICE_GAIN=" in lifted[-1] and "nearer" in lifted[-1]
    lines = check(quiet, "--gain", gain)
    assert "2 utterance(s)" in lines[-2] and sum("(noisy)" in line for line in lines) == 2
    assert "over the noise floor" in lines[-1] and "nearer" in lines[-1] and "HRI_VOICE_GAIN" not in lines[-1]
    lines = check(at_peak(word_stream("stop", "yes"), -20.0))
    assert "2 utterance(s)" in lines[-2] and lines[-1].startswith("fine: speech peaks at -20 dBFS")
    assert "dB over the noise" in lines[-1]


def test_levels_bench_places_the_speech_at_its_level_in_the_room() -> None:
    """bench/voice_levels.py: the speech's peak at the level asked (past full scale when asked: the stream clips it),
    `LEAD_S` into the room's hiss at the floor asked."""
    from bench.voice_levels import at_level, in_room, levels
    from bench.voice_walking import LEAD_S, TAIL_S
    from services.voice.audio import SAMPLE_RATE

    speech = np.sin(np.linspace(0, 200, 8000)) * 0.3
    assert np.isclose(np.abs(at_level(speech, -38.0)).max(), 10 ** (-38 / 20))
    assert np.isclose(np.abs(at_level(speech, 12.0)).max(), 10 ** (12 / 20))
    x = in_room(at_level(speech, -20.0), -70.0, np.random.default_rng(0))
    at = int(LEAD_S * SAMPLE_RATE)
    assert x.size == at + speech.size + int(TAIL_S * SAMPLE_RATE)
    assert round(20 * np.log10(np.sqrt(np.mean(x[:at] ** 2)))) == -70
    assert np.isclose(np.abs(x[at : at + speech.size]).max(), 0.1, atol=0.002)
    assert levels("-44,-26", "6") == [-44.0, -26.0, 6.0] and levels("-3", "") == [-3.0]
    # `--mic-rate`: sampled at 48 kHz and brought back by the service's resampler, a 1 kHz tone arrives as it was
    from bench.voice_bench import mic_pcm, through_mic

    tone = 0.3 * np.sin(2 * np.pi * 1000 * np.arange(SAMPLE_RATE) / SAMPLE_RATE)
    back = through_mic(tone, 48000)
    assert through_mic(tone, None) is tone and SAMPLE_RATE - back.size <= 0.1 * SAMPLE_RATE
    mid = slice(2000, 12000)
    assert np.sqrt(np.mean((back[mid] - tone[mid]) ** 2)) < 0.01 * np.sqrt(np.mean(tone[mid] ** 2))
    # voice_bench --mic-rate: a clip keeps its length and its timing; white hiss loses its top band (the resampler's
    # low-pass), which a real microphone's converter never passes either
    hiss = np.random.default_rng(1).normal(0.0, 0.05, SAMPLE_RATE)
    pcm = (hiss * 32767).astype("<i2").tobytes()
    out = np.frombuffer(mic_pcm(pcm, 44100), "<i2") / 32768.0
    assert mic_pcm(pcm, None) is pcm and out.size == hiss.size
    spectrum = np.abs(np.fft.rfft(out)) ** 2
    freqs = np.fft.rfftfreq(out.size, 1 / SAMPLE_RATE)
    top, speech_band = spectrum[freqs > 7800].mean(), spectrum[(freqs > 500) & (freqs < 6000)].mean()
    assert top < 0.01 * speech_band
    assert np.corrcoef(out[1000:-1000], hiss[1000:-1000])[0, 1] > 0.9


def test_advice_never_names_a_gain_over_the_limit() -> None:
    faint = Level.of(np.array([0, 20], "<i2").tobytes())  # -64 dBFS
    assert "HRI_VOICE_GAIN=45 would be over its 40" in (faint.advice(0.0) or "")  # -20 - -64.3, rounded up
    assert "raise the microphone's own gain" in (faint.advice(0.0) or "")
