"""The speech service as a process on a real Zenoh router: requests in, WAV files and states out."""

from __future__ import annotations

import itertools
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path
from subprocess import Popen

from schemas.messages import Health, HealthStatus, SpeechRequest
from services.runtime import ServiceContext
from services.speech.audio import wav_info
from tests.conftest import wait_for
from tests.speech.conftest import StateLog
from tests.speech.recognise import make_decoder, transcribe
from tests.speech.test_roundtrip import REFUSAL, is_refusal

Say = Callable[[str, str], SpeechRequest]
Start = Callable[..., Popen[bytes]]
LONG = "This sentence keeps the robot talking for about three seconds."


def test_request_is_spoken_into_a_wav_bracketed_by_states(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext, tmp_path: Path
) -> None:
    speech()
    say("refusal-1", REFUSAL)
    wait_for(lambda: states.ended("refusal-1"), timeout=15)
    assert states.events() == [(True, "refusal-1"), (False, "refusal-1")]
    wav = tmp_path / "out" / "refusal-1.wav"
    info = wav_info(wav)
    assert 1.0 < info.duration_s < 4.0 and info.active_fraction > 0.5
    start, end = states.times("refusal-1")
    # Folder output: "speaking" lasts the audio's real duration.
    assert info.duration_s - 0.1 <= end - start <= info.duration_s + 1.0
    assert is_refusal(transcribe(make_decoder(), wav))
    # the count is reported just after the end's state goes out: waited for, not read at once
    h = wait_for(lambda: (x := bus.query_health("speech")) is not None and x.detail.get("spoken") == 1 and x, timeout=5)
    assert isinstance(h, Health) and h.status == HealthStatus.OK
    assert h.detail["out"] == f"folder:{tmp_path / 'out'}"
    assert 0 < h.detail["ready_ms_last"] < 2000


def test_requests_are_spoken_in_order_one_at_a_time(speech: Start, say: Say, states: StateLog) -> None:
    speech("--rate", "400")
    ids = [f"r{i}" for i in range(4)]
    for i in ids:
        say(i, f"Reply number {i[1]}.")
    wait_for(lambda: states.ended(*ids), timeout=20)
    assert states.events() == [(s, i) for i in ids for s in (True, False)]
    for a, b in itertools.pairwise(ids):
        assert states.times(a)[1] <= states.times(b)[0]  # never two at once


def test_full_queue_drops_the_oldest_waiting(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext, tmp_path: Path
) -> None:
    speech("--queue-size", "2", "--max-age", "30")
    say("long", LONG)
    wait_for(lambda: (True, "long") in states.events(), timeout=10)
    for i in range(5):  # q0..q4 arrive while "long" is spoken; only the newest two can wait
        say(f"q{i}", "Yes.")
    wait_for(lambda: states.ended("long", "q3", "q4"), timeout=20)
    spoken = [i for s, i in states.events() if s]
    assert spoken == ["long", "q3", "q4"]
    assert not (tmp_path / "out" / "q0.wav").exists()
    # the count is reported just after the end's state goes out: waited for, not read at once
    h = wait_for(lambda: (x := bus.query_health("speech")) is not None and x.detail.get("spoken") == 3 and x, timeout=5)
    assert isinstance(h, Health) and h.detail["dropped_full"] == 3


def test_stale_requests_are_skipped_so_a_new_reply_does_not_wait(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext
) -> None:
    speech("--max-age", "0.5")
    say("long", LONG)
    wait_for(lambda: (True, "long") in states.events(), timeout=10)
    say("stale1", "Yes.")
    say("stale2", "No.")
    wait_for(lambda: states.ended("long"), timeout=15)
    say("fresh", REFUSAL)
    wait_for(lambda: states.ended("fresh"), timeout=10)
    assert [i for s, i in states.events() if s] == ["long", "fresh"]
    h = bus.query_health("speech")
    assert h is not None and h.detail["dropped_stale"] == 2


def test_bad_payloads_and_text_are_rejected_and_the_service_keeps_going(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext
) -> None:
    proc = speech("--max-chars", "50")
    key = bus.keys.speech_say
    bus.session.put(key, b"not json")
    bus.session.put(key, b'{"text": "no id"}')
    bus.session.put(key, b'{"id": "", "text": "empty id"}')
    say("empty", "   ")
    say("long", "a" * 51)
    say("marks", "?!...")
    say("ok", "Okay.")
    wait_for(lambda: states.ended("ok"), timeout=10)
    assert proc.poll() is None
    assert states.events() == [(True, "ok"), (False, "ok")]
    h = bus.query_health("speech")
    assert h is not None and h.rejected == 6 and h.detail["rejected_text"] == 3
    log = proc.log_path.read_text()  # type: ignore[attr-defined]
    assert "empty text" in log and "text too long: 51 characters" in log and "no letters or digits" in log


def test_duplicate_ids_are_spoken_once(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext
) -> None:
    speech()
    say("dup", "Yes.")
    say("dup", "Yes.")
    say("after", "No.")
    wait_for(lambda: states.ended("after"), timeout=10)
    assert [i for s, i in states.events() if s] == ["dup", "after"]
    h = bus.query_health("speech")
    assert h is not None and h.detail["duplicates"] == 1


def test_settings_come_from_the_environment(
    start_service: Start, say: Say, states: StateLog, bus: ServiceContext, tmp_path: Path
) -> None:
    out = tmp_path / "env-out"
    env = {"HRI_SPEECH_OUT": str(out), "HRI_SPEECH_VOICE": "en-gb", "HRI_SPEECH_RATE": "300",
           "HRI_SPEECH_VOLUME": "150"}
    start_service("speech", env=env)
    wait_for(states.ready, timeout=20)
    say("e1", REFUSAL)
    wait_for(lambda: states.ended("e1"), timeout=10)
    assert wav_info(out / "e1.wav").duration_s < 1.5  # 300 wpm: much shorter than at the default 175
    h = bus.query_health("speech")
    assert h is not None
    assert (h.detail["voice"], h.detail["rate"], h.detail["volume"]) == ("en-gb", 300, 150)


def test_default_output_is_the_state_folder(
    start_service: Start, say: Say, states: StateLog, tmp_path: Path
) -> None:
    # start_service gives every service HRI_STATE_DIR=tmp_path/state, as the demo does
    start_service("speech", env={"XDG_STATE_HOME": str(tmp_path / "state-home"), "HRI_SPEECH_OUT": ""})
    wait_for(states.ready, timeout=20)
    say("x1", "Yes.")
    wait_for(lambda: states.ended("x1"), timeout=10)
    assert (tmp_path / "state" / "speech" / "x1.wav").is_file()
    assert not (tmp_path / "state-home").exists()


def test_missing_espeak_ng_fails_health_with_install_command_and_recovers(
    speech: Start, say: Say, states: StateLog, bus: ServiceContext, tmp_path: Path
) -> None:
    path_dir = tmp_path / "bin"
    path_dir.mkdir()
    proc = speech(env={"PATH": str(path_dir)})
    h = bus.query_health("speech")
    assert h is not None and h.status == HealthStatus.FAILED
    assert "apt-get install espeak-ng" in h.detail["install"]
    assert "not found" in h.detail["engine_error"]
    say("lost", "Yes.")
    wait_for(lambda: (bus.query_health("speech") or h).detail.get("rejected_unavailable") == 1, timeout=5)
    assert proc.poll() is None and states.events() == []
    os.symlink("/usr/bin/espeak-ng", path_dir / "espeak-ng")  # installed while running: it retries
    wait_for(lambda: (bus.query_health("speech") or h).status == HealthStatus.OK, timeout=10, interval=0.2)
    say("found", "Yes.")
    wait_for(lambda: states.ended("found"), timeout=10)
    assert "apt-get install espeak-ng" in proc.log_path.read_text()  # type: ignore[attr-defined]


def test_missing_sound_device_degrades_and_writes_wavs_instead(
    start_service: Start, say: Say, states: StateLog, bus: ServiceContext, tmp_path: Path
) -> None:
    start_service("speech", "--out", "device:nosuchpcm")  # HRI_STATE_DIR=tmp_path/state
    wait_for(states.ready, timeout=20)
    h = bus.query_health("speech")
    assert h is not None and h.status == HealthStatus.DEGRADED
    assert h.detail["device"] == "device:nosuchpcm" and "HRI_SPEECH_OUT=<folder>" in h.detail["alternatives"]
    say("d1", "Yes.")
    wait_for(lambda: states.ended("d1"), timeout=10)
    assert (tmp_path / "state" / "speech" / "d1.wav").is_file()


def test_sigterm_while_speaking_ends_the_utterance_and_exits_cleanly(
    speech: Start, say: Say, states: StateLog
) -> None:
    proc = speech()
    say("long", LONG)
    wait_for(lambda: (True, "long") in states.events(), timeout=10)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(10) == 0
    assert time.monotonic() - t0 < 3.0
    wait_for(lambda: states.ended("long"), timeout=2)
    assert "cut short by shutdown" in proc.log_path.read_text()  # type: ignore[attr-defined]
