"""The view: the stick figure's forward kinematics, and the logging code fed from a recording into a
Rerun file (.rrd) that is read back."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from schemas.messages import (
    Decision,
    JointPositions,
    Mark,
    MarkObservation,
    MotionState,
    Posture,
    Shape,
    SpeechRequest,
    VoiceCommand,
)
from services.cli.mcapfile import McapWriter, read_recording
from services.cli.view import APP_ID, log_recording
from services.motion.joints import CENTER, JOINTS, SIT, STAND
from services.motion.present import joint_positions
from services.viewer.kinematics import ANKLE, CALF, THIGH, figure
from services.viewer.scene import ViewLogger
from services.vision.preview import PreviewSettings, make_preview


def _angles(pose: dict[int, float]) -> dict[str, float]:
    return {JOINTS[i].name: (t - CENTER) * 2 * math.pi / 4096 for i, t in pose.items()}


def test_straight_legs_put_the_hips_a_leg_length_above_the_ground() -> None:
    f = figure({})
    assert f.points["pelvis"][2] == pytest.approx(THIGH + CALF + ANKLE)
    assert f.points["r_sole"][2] == pytest.approx(0.0) and f.points["l_sole"][2] == pytest.approx(0.0)
    assert f.points["r_hip"][1] < 0 < f.points["l_hip"][1]  # y is left


def test_sitting_is_lower_than_standing_with_the_knees_forward_and_the_feet_flat() -> None:
    sit, stand = figure(_angles(SIT)), figure(_angles(STAND))
    assert sit.points["pelvis"][2] < 0.6 * stand.points["pelvis"][2]
    for f in (sit, stand):
        for side in "rl":
            assert f.points[f"{side}_knee"][0] > f.points[f"{side}_ankle"][0]  # knees ahead of the ankles
            sole, ankle = f.points[f"{side}_sole"], f.points[f"{side}_ankle"]
            assert np.linalg.norm(ankle - sole) == pytest.approx(ANKLE)
            assert sole[2] == pytest.approx(0.0, abs=0.01)  # both feet on the ground
            assert np.linalg.norm(f.points[f"{side}_knee"] - f.points[f"{side}_hip"]) == pytest.approx(THIGH)
    # Mirror image: the left side is the right side reflected in the y = 0 plane.
    for joint in ("knee", "ankle", "hand"):
        r, left = sit.points[f"r_{joint}"], sit.points[f"l_{joint}"]
        assert r[1] == pytest.approx(-left[1], abs=0.01) and r[2] == pytest.approx(left[2], abs=0.02)


def _recording(path: Path) -> None:
    w = McapWriter(path)
    t = 1_700_000_000.0
    image = np.full((480, 640, 3), 120, np.uint8)
    x = Mark(shape=Shape.X, confidence=0.93, box=(200, 120, 200, 200))
    for i in range(5):
        msg = make_preview(image, i, [x], t + i * 0.2, PreviewSettings())
        w.write("hri/op2/vision/preview", msg, msg.model_dump_json().encode())
    for i, pose in enumerate((SIT, STAND, STAND)):
        j: JointPositions = joint_positions({k: round(v) for k, v in pose.items()}, stamp=t + i * 0.04)
        w.write("hri/op2/motion/joints", j, j.model_dump_json().encode())
    for msg, key in (
        (MarkObservation(stamp=t, marks=[x]), "vision/marks"),
        (VoiceCommand(stamp=t + 0.5, command="go", text="go", confidence=0.9, engine="test"), "voice/command"),
        (Decision(stamp=t + 0.6, command="go", verdict="refuse", reason="danger_sign", situation="danger"),
         "reasoner/decision"),
        (SpeechRequest(stamp=t + 0.7, text="Sorry, I cannot do it.", id="s1"), "speech/say"),
        (MotionState(stamp=t + 0.8, posture=Posture.STANDING), "motion/state"),
    ):
        w.write(f"hri/op2/{key}", msg, msg.model_dump_json().encode())
    w.close()


def test_a_recording_drawn_into_an_rrd_file_has_every_entity(tmp_path: Path) -> None:
    mcap, rrd = tmp_path / "session.mcap", tmp_path / "session.rrd"
    _recording(mcap)
    rec = rr.RecordingStream(APP_ID)
    rec.save(rrd)
    logger = ViewLogger(rec)
    assert log_recording(read_recording(mcap), logger) == 13
    rec.flush()
    rec.disconnect()

    chunks = RrdReader(rrd).stream().to_chunks()
    rows: dict[str, int] = {}
    columns: dict[str, set[str]] = {}
    for c in chunks:
        rows[c.entity_path] = rows.get(c.entity_path, 0) + c.num_rows
        columns.setdefault(c.entity_path, set()).update(c.to_record_batch().schema.names)
    assert rows["/camera/image"] == 5 and "EncodedImage:blob" in columns["/camera/image"]
    assert rows["/camera/image/marks"] == 5 and "Boxes2D:labels" in columns["/camera/image/marks"]
    assert rows["/robot/skeleton"] == 3 and "LineStrips3D:strips" in columns["/robot/skeleton"]
    assert "/robot/joints" in rows
    for name in ("r_knee", "l_hip_pitch", "head_tilt"):
        assert "Scalars:scalars" in columns[f"/joints/{name}"]
    assert "Scalars:scalars" in columns["/state/situation"] and "Scalars:scalars" in columns["/state/posture"]
    # The text log: seen, heard, decided (refused, with the reason), said, posture.
    assert rows["/log"] == 5 and "TextLog:text" in columns["/log"]
    texts = [str(v) for c in chunks if c.entity_path == "/log"
             for v in c.to_record_batch().column("TextLog:text").to_pylist()]
    assert any("REFUSE go: danger_sign" in t for t in texts), texts


def test_the_live_feed_draws_what_comes_over_the_bus(bus, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from services.cli.view import LiveFeed
    from services.runtime import encoding_for
    from tests.conftest import wait_for

    rrd = tmp_path / "live.rrd"
    rec = rr.RecordingStream(APP_ID)
    rec.save(rrd)
    logger = ViewLogger(rec)
    feed = LiveFeed(bus, logger)
    joints = bus.publisher(bus.keys.motion_joints, JointPositions)
    decisions = bus.publisher(bus.keys.reasoner_decision, Decision)
    wait_for(lambda: joints.matched and decisions.matched, timeout=5)
    joints.put(joint_positions({k: round(v) for k, v in STAND.items()}))
    decisions.put(Decision(command="stop", verdict="obey", reason="ok", action="stop", situation="safe"))
    bus.session.put(bus.keys.motion_joints, b'{"ids": "garbage"}')  # no model named: skipped
    bus.session.put(bus.keys.motion_joints, b'{"ids": "garbage"}', encoding=encoding_for(JointPositions))
    wait_for(lambda: logger.logged == 2 and bus.counters.rejected == 1, timeout=5)  # invalid: counted
    feed.close()
    rec.flush()
    rec.disconnect()
    paths = {c.entity_path for c in RrdReader(rrd).stream().to_chunks()}
    assert {"/robot/skeleton", "/joints/r_knee", "/state/situation", "/log"} <= paths
