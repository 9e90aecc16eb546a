"""The wire contract of the HRI system: message models and key expressions.

This package imports nothing else of ours, so any program (a service, a test, a
third-party tool) can speak the protocol by depending on it alone.
"""

from schemas.keys import Keys, validate_robot_id
from schemas.messages import (
    MODELS,
    Action,
    Command,
    Decision,
    Header,
    Health,
    HealthStatus,
    Mark,
    MarkObservation,
    MotionGoal,
    MotionState,
    Posture,
    Reason,
    SceneCommand,
    Shape,
    Situation,
    SpeechRequest,
    SpeechState,
    Verdict,
    VoiceCommand,
)

__all__ = [
    "MODELS",
    "Action",
    "Command",
    "Decision",
    "Header",
    "Health",
    "HealthStatus",
    "Keys",
    "Mark",
    "MarkObservation",
    "MotionGoal",
    "MotionState",
    "Posture",
    "Reason",
    "SceneCommand",
    "Shape",
    "Situation",
    "SpeechRequest",
    "SpeechState",
    "Verdict",
    "VoiceCommand",
    "validate_robot_id",
]
