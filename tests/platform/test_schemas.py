"""The wire contract: round trips, rejection of bad values, tolerance of unknown fields, keys."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from schemas import (
    MODELS,
    Action,
    Command,
    Decision,
    Health,
    Keys,
    Mark,
    MarkObservation,
    MotionGoal,
    MotionState,
    Posture,
    Reason,
    SpeechRequest,
    SpeechState,
    Verdict,
    VoiceCommand,
)

SAMPLES = [
    MarkObservation(marks=[Mark(shape="X", confidence=0.97, box=(10, 20, 30, 40))], frame=7),
    MarkObservation(marks=[], frame=0),
    VoiceCommand(command="go", text="go", confidence=0.8, engine="pocketsphinx"),
    VoiceCommand(command=None, text="table", confidence=0.1, engine="pocketsphinx"),
    MotionGoal(action="walk_forward", goal_id="g1", cause_stamp=12.5),
    MotionState(posture="walking", action="walk_forward", goal_id="g1", bus_ok=True),
    Decision(command="go", verdict="refuse", reason="danger_sign", action=None, situation="danger",
             say="Sorry, I cannot do it."),
    SpeechRequest(text="Sorry, I cannot do it.", id="s1"),
    SpeechState(speaking=True, id="s1", text="Sorry, I cannot do it."),
    Health(service="vision", status="degraded", uptime_s=3.2, received=1, published=2, rejected=3,
           detail={"device": "camera:0"}),
]


@pytest.mark.parametrize("msg", SAMPLES, ids=lambda m: type(m).__name__)
def test_round_trip_through_json(msg) -> None:
    again = type(msg).model_validate_json(msg.model_dump_json())
    assert again == msg


def test_every_message_carries_stamp_and_seq() -> None:
    for model in MODELS.values():
        assert {"stamp", "seq"} <= set(model.model_fields), model.__name__


def test_enums_serialise_as_the_contract_strings() -> None:
    data = json.loads(SAMPLES[6].model_dump_json())
    assert data["verdict"] == "refuse" and data["reason"] == "danger_sign" and data["situation"] == "danger"
    assert {c.value for c in Command} == {"stand", "down", "yes", "no", "go", "stop", "why"}
    assert {a.value for a in Action} == {"stand_up", "sit_down", "nod", "shake_head", "walk_forward", "stop"}
    assert {p.value for p in Posture} == {"sitting", "standing", "walking", "moving", "unknown"}
    assert {v.value for v in Verdict} == {"obey", "refuse", "ignore", "ask"}
    assert {r.value for r in Reason} == {"ok", "danger_sign", "not_understood", "already_done", "busy", "confirm"}


@pytest.mark.parametrize(
    ("model", "payload"),
    [
        (VoiceCommand, {"command": "dance", "text": "dance", "confidence": 0.9, "engine": "x"}),
        (VoiceCommand, {"command": "go", "text": "go", "confidence": 1.5, "engine": "x"}),
        (VoiceCommand, {"command": "go", "text": "go", "confidence": -0.1, "engine": "x"}),
        (MarkObservation, {"marks": [{"shape": "SQUARE", "confidence": 0.5, "box": [0, 0, 1, 1]}]}),
        (MarkObservation, {"marks": [{"shape": "X", "confidence": 0.5, "box": [0, 0, 1]}]}),
        (MarkObservation, {"marks": [{"shape": "X", "confidence": 0.5, "box": [0, 0, -1, 1]}], "frame": 1}),
        (MarkObservation, {"marks": [], "frame": -1}),
        (MotionGoal, {"action": "fly", "goal_id": "g"}),
        (MotionGoal, {"action": "nod", "goal_id": ""}),
        (MotionState, {"posture": "lying"}),
        (Decision, {"verdict": "maybe", "reason": "ok", "situation": "safe"}),
        (Decision, {"verdict": "obey", "reason": "because", "situation": "safe"}),
        (Decision, {"verdict": "obey", "reason": "ok", "situation": "fine"}),
        (SpeechRequest, {"text": "hi"}),
        (Health, {"service": "x", "status": "bad", "uptime_s": 1}),
        (Health, {"service": "x", "status": "ok", "uptime_s": 1, "rejected": -2}),
        (VoiceCommand, {"command": "go", "text": "go", "confidence": 0.9, "engine": "x", "seq": -1}),
    ],
)
def test_bad_values_are_rejected(model, payload) -> None:
    with pytest.raises(ValidationError):
        model.model_validate(payload)


def test_not_json_is_rejected() -> None:
    with pytest.raises(ValidationError):
        VoiceCommand.model_validate_json(b"not json")


def test_unknown_fields_are_tolerated() -> None:
    """A newer publisher may add fields; an older receiver must still accept the message."""
    msg = MotionGoal.model_validate({"action": "nod", "goal_id": "g", "speed": "fast", "seq": 3})
    assert msg.action is Action.NOD and msg.seq == 3


@given(
    shape=st.sampled_from(["X", "O", "TRIANGLE"]),
    conf=st.floats(0, 1),
    box=st.tuples(*[st.integers(0, 4096)] * 4),
    frame=st.integers(0, 2**40),
)
def test_mark_round_trip_property(shape: str, conf: float, box: tuple[int, int, int, int], frame: int) -> None:
    msg = MarkObservation(marks=[Mark(shape=shape, confidence=conf, box=box)], frame=frame)
    assert MarkObservation.model_validate_json(msg.model_dump_json()) == msg


def test_keys_are_built_from_the_robot_id() -> None:
    k = Keys("op2")
    assert k.vision_marks == "hri/op2/vision/marks"
    assert k.voice_command == "hri/op2/voice/command"
    assert k.reasoner_decision == "hri/op2/reasoner/decision"
    assert k.motion_goal == "hri/op2/motion/goal"
    assert k.motion_state == "hri/op2/motion/state"
    assert k.speech_say == "hri/op2/speech/say"
    assert k.speech_state == "hri/op2/speech/state"
    assert k.health("motion") == "hri/op2/motion/health"
    assert k.alive("speech") == "hri/op2/alive/speech"
    assert Keys("lab-7").all == "hri/lab-7/**"
    assert Keys().robot == "op2"


@pytest.mark.parametrize("bad", ["", "a/b", "*", "**", "op2$", "a b", "x?y", "r#1"])
def test_bad_robot_ids_are_refused(bad: str) -> None:
    with pytest.raises(ValueError, match="robot id"):
        Keys(bad)
