"""Pydantic v2 models of every message in DESIGN.md.

Field names are the contract: add fields freely, never rename these. Unknown fields
are ignored on receipt so that a newer publisher never breaks an older receiver.
"""

from __future__ import annotations

import time
from enum import StrEnum
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field

Confidence = Annotated[float, Field(ge=0.0, le=1.0)]
NonNegInt = Annotated[int, Field(ge=0)]


class Shape(StrEnum):
    X = "X"
    O = "O"  # noqa: E741 - the mark is literally called O
    TRIANGLE = "TRIANGLE"

    @property
    def is_danger(self) -> bool:
        return self in (Shape.X, Shape.TRIANGLE)


class Command(StrEnum):
    STAND = "stand"
    DOWN = "down"
    YES = "yes"
    NO = "no"
    GO = "go"
    STOP = "stop"
    WHY = "why"

    @property
    def moves_robot(self) -> bool:
        """"why" asks for an explanation; it never moves the robot."""
        return self is not Command.WHY


class Action(StrEnum):
    STAND_UP = "stand_up"
    SIT_DOWN = "sit_down"
    NOD = "nod"
    SHAKE_HEAD = "shake_head"
    WALK_FORWARD = "walk_forward"
    STOP = "stop"


class Posture(StrEnum):
    SITTING = "sitting"
    STANDING = "standing"
    WALKING = "walking"
    MOVING = "moving"
    UNKNOWN = "unknown"


class Verdict(StrEnum):
    OBEY = "obey"
    REFUSE = "refuse"
    IGNORE = "ignore"
    ASK = "ask"


class Reason(StrEnum):
    """Why a directive was (not) carried out, after Briggs and Scheutz (2015)."""

    OK = "ok"
    DANGER_SIGN = "danger_sign"
    NOT_UNDERSTOOD = "not_understood"
    ALREADY_DONE = "already_done"
    BUSY = "busy"
    CONFIRM = "confirm"


class Situation(StrEnum):
    SAFE = "safe"
    DANGER = "danger"


class HealthStatus(StrEnum):
    OK = "ok"
    DEGRADED = "degraded"
    FAILED = "failed"


class Header(BaseModel):
    """Fields every message carries: when it was made and the publisher's sequence number."""

    model_config = ConfigDict(extra="ignore", frozen=False, use_enum_values=False)

    stamp: float = Field(default_factory=time.time, ge=0.0, description="UNIX seconds")
    seq: NonNegInt = Field(default=0, description="monotonic per publisher")


class Mark(BaseModel):
    model_config = ConfigDict(extra="ignore")

    shape: Shape
    confidence: Confidence
    box: tuple[NonNegInt, NonNegInt, NonNegInt, NonNegInt] = Field(
        description="x, y, width, height in pixels"
    )


class MarkObservation(Header):
    marks: list[Mark] = Field(default_factory=list)
    frame: NonNegInt = 0


class VoiceCommand(Header):
    command: Command | None
    text: str = ""
    confidence: Confidence = 0.0
    engine: str = ""


class MotionGoal(Header):
    action: Action
    goal_id: str = Field(min_length=1)
    cause_stamp: float | None = Field(
        default=None, description="stamp of the input message (command or marks) that led to this goal"
    )


class MotionState(Header):
    posture: Posture
    action: Action | None = None
    goal_id: str | None = None
    bus_ok: bool = True
    goal_stamp: float | None = Field(default=None, description="stamp of the goal being carried out")
    first_write: float | None = Field(
        default=None, description="UNIX time of the first servo write that carried the current goal"
    )


class Decision(Header):
    command: Command | None = None
    verdict: Verdict
    reason: Reason
    action: Action | None = None
    situation: Situation
    say: str | None = None
    cause_stamp: float | None = Field(default=None, description="stamp of the input that caused it")


class SpeechRequest(Header):
    text: str
    id: str = Field(min_length=1)


class SpeechState(Header):
    speaking: bool
    id: str | None = None
    text: str | None = None


class Health(Header):
    service: str
    status: HealthStatus
    uptime_s: float = Field(ge=0.0)
    received: NonNegInt = 0
    published: NonNegInt = 0
    rejected: NonNegInt = 0
    detail: dict[str, Any] = Field(default_factory=dict)


class Evidence(BaseModel):
    """One thing the robot experienced that an explanation rests on."""

    model_config = ConfigDict(extra="ignore")

    kind: str = Field(description='"mark" (seen) or "command" (heard)')
    what: str = Field(description="the mark's shape or the command word")
    stamp: float = Field(ge=0.0, description="UNIX seconds when it was seen or heard")
    ago_s: float | None = Field(default=None, ge=0.0, description="seconds before the explanation")
    episode: NonNegInt | None = Field(default=None, description="Soar episodic-memory episode number")


class Explanation(Header):
    """The answer to "why": the latest decision, the condition behind it, and the evidence recalled."""

    decision: Decision | None = Field(default=None, description="the decision explained (null: nothing yet)")
    reason: Reason | None = None
    text: str = Field(description="the sentence the robot says")
    evidence: list[Evidence] = Field(default_factory=list)
    episode: NonNegInt | None = Field(default=None, description="the episode retrieved from episodic memory")


class VisionPreview(Header):
    """A small JPEG of what the camera sees, with the marks found in it (a viewer's feed, low rate)."""

    frame: NonNegInt = 0
    width: NonNegInt = 0
    height: NonNegInt = 0
    jpeg: str = Field(description="base64 of the JPEG image")
    marks: list[Mark] = Field(default_factory=list, description="boxes in the preview's own pixels")


class JointPositions(Header):
    """Present positions of the robot's joints, read from the servos (or the simulated bus)."""

    ids: list[NonNegInt] = Field(description="Dynamixel ids, 1..20")
    names: list[str] = Field(default_factory=list)
    ticks: list[NonNegInt] = Field(default_factory=list, description="raw present positions, 0..4095")
    radians: list[float] = Field(description="angle from the servo's centre (2048), radians")


class SceneCommand(Header):
    """Simulator control, not robot data: what the synthetic camera scene holds up (null: nothing)."""

    shape: Shape | None = None


MODELS: dict[str, type[Header]] = {
    m.__name__: m
    for m in (
        MarkObservation,
        VoiceCommand,
        MotionGoal,
        MotionState,
        Decision,
        SpeechRequest,
        SpeechState,
        Health,
        SceneCommand,
        Explanation,
        VisionPreview,
        JointPositions,
    )
}
"""Every top-level message model by name (the name is the encoding schema on the wire)."""
