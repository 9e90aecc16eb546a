"""The OP2's twenty joints: Dynamixel IDs, names, position limits and the named poses.

Positions are MX-28 ticks (0..4095, centre 2048, about 11.378 ticks per degree). Poses and the
sit/stand leg values come from the ROBOTIS motion file (see REFERENCE.md); the arm pose is the
ROBOTIS walking module's arm pose converted to ticks.
"""

from __future__ import annotations

from dataclasses import dataclass

CENTER = 2048
TICKS_PER_DEGREE = 4096 / 360.0
CM740_ID = 200
CM740_MODEL = 0x7400
MX28_MODEL = 29


def deg(angle: float) -> float:
    """Degrees to a tick offset from the centre."""
    return angle * TICKS_PER_DEGREE


@dataclass(frozen=True)
class Joint:
    id: int
    name: str
    lo: int
    hi: int

    def clamp(self, ticks: float) -> int:
        return round(min(max(ticks, self.lo), self.hi))


def _lim(lo_deg: float, hi_deg: float) -> tuple[int, int]:
    return round(CENTER + deg(lo_deg)), round(CENTER + deg(hi_deg))


_TABLE: tuple[tuple[int, str, tuple[int, int]], ...] = (
    (1, "r_shoulder_pitch", _lim(-90, 90)),
    (2, "l_shoulder_pitch", _lim(-90, 90)),
    (3, "r_shoulder_roll", _lim(-90, 20)),
    (4, "l_shoulder_roll", _lim(-20, 90)),
    (5, "r_elbow", _lim(-20, 160)),
    (6, "l_elbow", _lim(-160, 20)),
    (7, "r_hip_yaw", _lim(-45, 45)),
    (8, "l_hip_yaw", _lim(-45, 45)),
    (9, "r_hip_roll", _lim(-45, 45)),
    (10, "l_hip_roll", _lim(-45, 45)),
    (11, "r_hip_pitch", _lim(-100, 45)),
    (12, "l_hip_pitch", _lim(-45, 100)),
    (13, "r_knee", _lim(-5, 135)),
    (14, "l_knee", _lim(-135, 5)),
    (15, "r_ankle_pitch", _lim(-45, 80)),
    (16, "l_ankle_pitch", _lim(-80, 45)),
    (17, "r_ankle_roll", _lim(-45, 45)),
    (18, "l_ankle_roll", _lim(-45, 45)),
    (19, "head_pan", _lim(-80, 80)),
    (20, "head_tilt", _lim(-10, 68)),
)

JOINTS: dict[int, Joint] = {jid: Joint(jid, name, lo, hi) for jid, name, (lo, hi) in _TABLE}
JOINT_IDS: tuple[int, ...] = tuple(JOINTS)
BY_NAME: dict[str, int] = {j.name: j.id for j in JOINTS.values()}
LEG_IDS: tuple[int, ...] = tuple(range(7, 19))
HEAD_PAN, HEAD_TILT = 19, 20
HEAD_IDS: tuple[int, ...] = (HEAD_PAN, HEAD_TILT)
BODY_IDS: tuple[int, ...] = tuple(i for i in JOINT_IDS if i not in HEAD_IDS)

Pose = dict[int, float]

ARMS: Pose = {1: 1498, 2: 2518, 3: 1845, 4: 2248, 5: 2381, 6: 1711}
HEAD_HOME: Pose = {HEAD_PAN: CENTER, HEAD_TILT: CENTER}
_NEUTRAL_LEGS: Pose = {7: CENTER, 8: CENTER, 9: CENTER, 10: CENTER, 17: CENTER, 18: CENTER}

SIT: Pose = {**ARMS, **_NEUTRAL_LEGS, 11: 1277, 12: 2797, 13: 3513, 14: 571, 15: 2843, 16: 1240, **HEAD_HOME}
STAND: Pose = {
    **ARMS,
    **_NEUTRAL_LEGS,
    11: 1660,
    12: 2436,
    13: 2646,
    14: 1450,
    15: 2409,
    16: 1687,
    **HEAD_HOME,
}

NOD_TILT: tuple[int, int] = (2337, 2004)
SHAKE_PAN: tuple[int, int] = (1880, 2213)


def describe(jid: int) -> str:
    """`ID 13 (r_knee)`, for error messages that name the servo."""
    joint = JOINTS.get(jid)
    return f"ID {jid} ({joint.name})" if joint else f"ID {jid}"


def clamp_pose(pose: Pose) -> dict[int, int]:
    """Every goal goes through the joint limits."""
    return {jid: JOINTS[jid].clamp(v) for jid, v in pose.items() if jid in JOINTS}


def pose_error(present: dict[int, int], pose: Pose, ids: tuple[int, ...] = LEG_IDS) -> float:
    """Largest absolute difference in ticks between `present` and `pose` over `ids` present in both."""
    errs = [abs(present[i] - pose[i]) for i in ids if i in present and i in pose]
    return max(errs) if errs else float("inf")
