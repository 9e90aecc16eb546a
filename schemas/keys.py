"""The one place that builds key expressions from the robot id."""

from __future__ import annotations

import re
from dataclasses import dataclass

SERVICES: tuple[str, ...] = ("vision", "voice", "reasoner", "motion", "speech")
"""The five services of DESIGN.md, in start-up order."""

_ROBOT_ID = re.compile(r"^[A-Za-z0-9_\-.]+$")


def validate_robot_id(robot: str) -> str:
    """A robot id is one key chunk: letters, digits, `_ - .`; no `/`, wildcards or `$`."""
    if not _ROBOT_ID.fullmatch(robot or ""):
        raise ValueError(
            f"invalid robot id {robot!r}: use letters, digits, '_', '-' or '.' (it becomes one "
            "chunk of the key expression hri/<robot>/...)"
        )
    return robot


@dataclass(frozen=True)
class Keys:
    """Key expressions of one robot, `hri/<robot>/...`."""

    robot: str = "op2"

    def __post_init__(self) -> None:
        validate_robot_id(self.robot)

    @property
    def prefix(self) -> str:
        return f"hri/{self.robot}"

    @property
    def all(self) -> str:
        return f"{self.prefix}/**"

    @property
    def vision_marks(self) -> str:
        return f"{self.prefix}/vision/marks"

    @property
    def vision_scene(self) -> str:
        """Simulator control: what the synthetic scene source shows (`SceneCommand`)."""
        return f"{self.prefix}/vision/scene"

    @property
    def reasoner_soar(self) -> str:
        """Queryable: run a Soar command on the live agent (payload: the command, reply: its output)."""
        return f"{self.prefix}/reasoner/soar"

    @property
    def reasoner_explain(self) -> str:
        """Queryable: the explanation of the latest decision (`Explanation`, JSON)."""
        return f"{self.prefix}/reasoner/explain"

    @property
    def vision_preview(self) -> str:
        """Low-rate preview image with boxes (`VisionPreview`), published only while subscribed."""
        return f"{self.prefix}/vision/preview"

    @property
    def motion_joints(self) -> str:
        """Present joint positions (`JointPositions`), about 25 Hz."""
        return f"{self.prefix}/motion/joints"

    @property
    def voice_command(self) -> str:
        return f"{self.prefix}/voice/command"

    @property
    def reasoner_decision(self) -> str:
        return f"{self.prefix}/reasoner/decision"

    @property
    def motion_goal(self) -> str:
        return f"{self.prefix}/motion/goal"

    @property
    def motion_state(self) -> str:
        return f"{self.prefix}/motion/state"

    @property
    def speech_say(self) -> str:
        return f"{self.prefix}/speech/say"

    @property
    def speech_state(self) -> str:
        return f"{self.prefix}/speech/state"

    def health(self, service: str) -> str:
        return f"{self.prefix}/{_service(service)}/health"

    @property
    def health_all(self) -> str:
        return f"{self.prefix}/*/health"

    def alive(self, service: str) -> str:
        return f"{self.prefix}/alive/{_service(service)}"

    @property
    def alive_all(self) -> str:
        return f"{self.prefix}/alive/*"

    def service_of_alive(self, key: str) -> str:
        """`hri/op2/alive/vision` -> `vision`."""
        return key.rsplit("/", 1)[-1]


def _service(name: str) -> str:
    if not _ROBOT_ID.fullmatch(name or ""):
        raise ValueError(f"invalid service name {name!r}")
    return name
