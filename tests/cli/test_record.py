"""Recording the bus to MCAP and replaying it: the recorder in-process, and `hri record` / `hri replay`
as users run them, on a real Zenoh router."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import zenoh

from schemas.messages import Command, Decision, MarkObservation, VoiceCommand
from services.cli.mcapfile import read_recording
from services.cli.record import McapRecorder
from services.runtime import ServiceContext, encoding_for
from tests.conftest import ROOT, wait_for


def _hri(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "services.cli", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=timeout, env={**__import__("os").environ, "COLUMNS": "200"})


def test_recorder_keeps_valid_messages_and_counts_the_rest(bus: ServiceContext, tmp_path: Path) -> None:
    path = tmp_path / "r.mcap"
    rec = McapRecorder(bus, path)
    voice = bus.publisher(bus.keys.voice_command, VoiceCommand)
    marks = bus.publisher(bus.keys.vision_marks, MarkObservation)
    for word in ("stand", "go", "stop"):
        voice.put(VoiceCommand(command=Command(word), text=word, confidence=0.9))
    marks.put(MarkObservation(frame=1))
    bus.session.put(bus.keys.voice_command, b'{"command": "fly"}', encoding=encoding_for(VoiceCommand))
    bus.session.put(bus.keys.prefix + "/notes", b"plain text", encoding=zenoh.Encoding.TEXT_PLAIN)
    wait_for(lambda: rec.summary.messages + sum(rec.summary.rejected.values()) == 6, timeout=5)
    summary = rec.close()
    assert summary.counts == {bus.keys.voice_command: 3, bus.keys.vision_marks: 1}
    assert summary.rejected == {bus.keys.voice_command: 1, bus.keys.prefix + "/notes": 1}
    back = list(read_recording(path))
    assert [m.decode().command for m in back if m.key == bus.keys.voice_command] == ["stand", "go", "stop"]
    assert all(m.log_time == m.decode().stamp for m in back)
    assert summary.table().row_count == 3


def test_hri_record_then_replay_and_check(bus: ServiceContext, router_endpoint: str, tmp_path: Path) -> None:
    path = tmp_path / "cli.mcap"
    common = ("--connect", router_endpoint, "--robot", bus.keys.robot)
    proc = subprocess.Popen([sys.executable, "-m", "services.cli", "record", str(path), "--duration", "4", *common],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**__import__("os").environ, "COLUMNS": "200"})
    voice = bus.publisher(bus.keys.voice_command, VoiceCommand)
    decisions = bus.publisher(bus.keys.reasoner_decision, Decision)
    wait_for(lambda: voice.matched, timeout=20)  # the recorder has subscribed
    for word in ("stand", "go"):
        voice.put(VoiceCommand(command=Command(word), text=word, confidence=0.9))
        time.sleep(0.3)
    decisions.put(Decision(command="go", verdict="refuse", reason="danger_sign", situation="danger"))
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, out
    assert f"{bus.keys.voice_command}" in out and "3 messages" in out, out

    heard: list[tuple[float, VoiceCommand]] = []
    bus.subscribe(bus.keys.voice_command, VoiceCommand, lambda m: heard.append((time.monotonic(), m)))
    done = _hri("replay", str(path), *common)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "replayed 2 message(s)" in done.stdout
    wait_for(lambda: len(heard) == 2, timeout=5)
    assert [m.command for _, m in heard] == ["stand", "go"]
    assert heard[1][0] - heard[0][0] > 0.2  # the recorded pace

    # No reasoner on this bus: the recorded refusal is not made again, and --check says so.
    check = _hri("replay", str(path), "--check", "--rate", "0", "--settle", "0.5", *common)
    assert check.returncode == 1, check.stdout + check.stderr
    assert "1 decision(s) recorded, 0 made now" in check.stdout
    assert "recorded go -> refuse danger_sign" in check.stdout


def test_hri_replay_refuses_what_is_not_a_recording(tmp_path: Path) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file at all")
    for path in (bad, tmp_path / "missing.mcap"):
        done = _hri("replay", str(path), "--connect", "tcp/127.0.0.1:1")
        assert done.returncode == 2 and str(path) in done.stderr, done.stderr
    exists = _hri("record", str(bad), "--connect", "tcp/127.0.0.1:1")
    assert exists.returncode == 2 and "exists" in exists.stderr


def test_a_recording_cut_short_reads_up_to_its_last_complete_chunk(tmp_path: Path) -> None:
    from services.cli.mcapfile import McapWriter, RecordingError
    from services.motion.joints import SIT
    from services.motion.present import joint_positions

    path = tmp_path / "full.mcap"
    w = McapWriter(path)
    for i in range(3000):  # several chunks
        j = joint_positions({k: round(v) + i % 7 for k, v in SIT.items()}, stamp=1e9 + i * 0.04)
        w.write("hri/op2/motion/joints", j, j.model_dump_json().encode())
    w.close()
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"  # as a killed recorder leaves it: no summary, no footer
    cut.write_bytes(data[: len(data) * 6 // 10])
    back = list(read_recording(cut))
    assert 1000 < len(back) < 3000
    assert [m.log_time for m in back] == [1e9 + i * 0.04 for i in range(len(back))]
    cut.write_bytes(data[:100])
    try:
        list(read_recording(cut))
        raise AssertionError("a header alone is not a recording")
    except RecordingError as exc:
        assert str(cut) in str(exc)


def test_recording_without_images_leaves_the_preview_unwatched(bus: ServiceContext, tmp_path: Path) -> None:
    from schemas.messages import VisionPreview
    from services.cli.record import without_images

    preview = bus.publisher(bus.keys.vision_preview, VisionPreview)
    joints_key = bus.keys.motion_joints
    rec = McapRecorder(bus, tmp_path / "n.mcap", without_images(bus.keys))
    marks = bus.publisher(bus.keys.vision_marks, MarkObservation)
    wait_for(lambda: marks.matched, timeout=5)
    time.sleep(0.3)
    assert not preview.matched  # so vision encodes no preview for this recorder
    bus.session.put(joints_key, b"{}")  # a key the list still covers (motion/**): seen, rejected
    wait_for(lambda: rec.summary.rejected[joints_key] == 1, timeout=5)
    rec.close()


def test_a_recorder_whose_writer_falls_behind_drops_and_counts_instead_of_growing(bus: ServiceContext,
                                                                                   tmp_path: Path) -> None:
    rec = McapRecorder(bus, tmp_path / "behind.mcap", max_queued_bytes=1000)
    release = __import__("threading").Event()
    write = rec._write

    def stalled(key: str, encoding: str, data: bytes) -> None:  # a disk that hangs until released
        release.wait(10)
        write(key, encoding, data)

    rec._write = stalled  # type: ignore[method-assign]
    voice = bus.publisher(bus.keys.voice_command, VoiceCommand)
    size = len(VoiceCommand(command=Command.STOP, text="stop", confidence=0.9).model_dump_json())
    for _ in range(20):
        voice.put(VoiceCommand(command=Command.STOP, text="stop", confidence=0.9))
    wait_for(lambda: rec.summary.dropped[bus.keys.voice_command] >= 20 - 1000 // size, timeout=5)
    release.set()
    summary = rec.close()
    kept, dropped = summary.counts[bus.keys.voice_command], summary.dropped[bus.keys.voice_command]
    assert kept + dropped == 20 and 0 < kept <= 1000 // size  # a sample counts until it is written
    assert len(list(read_recording(tmp_path / "behind.mcap"))) == kept
    assert rec._queued == 0 and "dropped" in [c.header for c in summary.table().columns]
