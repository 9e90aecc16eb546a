"""Forward kinematics of the OP2 for a stick figure: joint angles in, 3D points of the body out.

Frame: x forward, y left, z up, metres. The chain is built from the pelvis centre; the figure is
then turned so that the feet are flat (the robot stands on them) and lifted so that the lower
foot's sole is at z = 0. Leg links are the ROBOTIS framework's (thigh 93 mm, calf 93 mm, ankle
33.5 mm, hips 37 mm either side of the centre: REFERENCE.md). Torso, arm and head lengths are
approximate, from the DARwIn-OP model (the OP2 shares its skeleton): enough to draw, not to control.

Angles are each servo's offset from its centre (radians, as `JointPositions.radians`). The left and
right servos of a pair are mounted mirrored, so the same movement has opposite signs on the two
sides (the sitting pose: right hip pitch -68 degrees, left +66).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

HIP_SIDE = 0.037
THIGH = 0.093
CALF = 0.093
ANKLE = 0.0335
PELVIS_TO_SHOULDERS = 0.1222
SHOULDER_SIDE = 0.082
UPPER_ARM = 0.060
LOWER_ARM = 0.129
NECK = 0.051
HEAD = 0.045
SHOULDER_PITCH_ZERO = np.pi / 4
"""Assumed: a shoulder-pitch servo at its centre holds the arm 45 degrees back, so that the ROBOTIS arm
pose (about -48 degrees) hangs the arms down by the sides."""

SEGMENTS: tuple[tuple[str, str], ...] = (
    ("r_hip", "l_hip"), ("pelvis", "neck"), ("r_shoulder", "l_shoulder"), ("neck", "head"),
    ("r_hip", "r_knee"), ("r_knee", "r_ankle"), ("r_ankle", "r_sole"),
    ("l_hip", "l_knee"), ("l_knee", "l_ankle"), ("l_ankle", "l_sole"),
    ("r_shoulder", "r_elbow"), ("r_elbow", "r_hand"), ("l_shoulder", "l_elbow"), ("l_elbow", "l_hand"),
)
"""The figure's bones, as pairs of point names."""


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class Figure:
    points: dict[str, np.ndarray]

    def strips(self) -> list[list[list[float]]]:
        """The bones as line strips (for `rerun.LineStrips3D`)."""
        return [[self.points[a].tolist(), self.points[b].tolist()] for a, b in SEGMENTS]

    def joints(self) -> tuple[list[str], list[list[float]]]:
        names = sorted(self.points)
        return names, [self.points[n].tolist() for n in names]


def _leg(q: Mapping[str, float], side: str) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Points of one leg from its hip, and the foot's orientation; `sign` undoes the mirrored mounting."""
    sign = 1.0 if side == "r" else -1.0
    hip = np.array([0.0, -HIP_SIDE if side == "r" else HIP_SIDE, 0.0])
    # Pitch about y: a negative angle swings the limb forward. Right-side servos turn that way for
    # a positive knee and a negative hip pitch; the left side is mirrored.
    r = _rz(q.get(f"{side}_hip_yaw", 0.0)) @ _rx(q.get(f"{side}_hip_roll", 0.0)) @ _ry(
        sign * q.get(f"{side}_hip_pitch", 0.0))
    knee = hip + r @ DOWN * THIGH
    r = r @ _ry(sign * q.get(f"{side}_knee", 0.0))
    ankle = knee + r @ DOWN * CALF
    r = r @ _ry(-sign * q.get(f"{side}_ankle_pitch", 0.0)) @ _rx(q.get(f"{side}_ankle_roll", 0.0))
    sole = ankle + r @ DOWN * ANKLE
    return {f"{side}_hip": hip, f"{side}_knee": knee, f"{side}_ankle": ankle, f"{side}_sole": sole}, r


def _arm(q: Mapping[str, float], side: str) -> dict[str, np.ndarray]:
    sign = 1.0 if side == "r" else -1.0
    shoulder = np.array([0.0, -SHOULDER_SIDE if side == "r" else SHOULDER_SIDE, PELVIS_TO_SHOULDERS])
    r = _ry(sign * q.get(f"{side}_shoulder_pitch", 0.0) + SHOULDER_PITCH_ZERO) @ _rx(
        q.get(f"{side}_shoulder_roll", 0.0))
    elbow = shoulder + r @ DOWN * UPPER_ARM
    r = r @ _ry(-sign * q.get(f"{side}_elbow", 0.0))
    hand = elbow + r @ DOWN * LOWER_ARM
    return {f"{side}_shoulder": shoulder, f"{side}_elbow": elbow, f"{side}_hand": hand}


def figure(angles: Mapping[str, float]) -> Figure:
    """The stick figure for joint angles by joint name (missing joints are taken as centred)."""
    right, r_foot = _leg(angles, "r")
    left, l_foot = _leg(angles, "l")
    points: dict[str, np.ndarray] = {"pelvis": np.zeros(3), **right, **left, **_arm(angles, "r"),
                                     **_arm(angles, "l")}
    points["neck"] = np.array([0.0, 0.0, PELVIS_TO_SHOULDERS])
    head = _rz(angles.get("head_pan", 0.0)) @ _ry(-angles.get("head_tilt", 0.0)) @ np.array([0.0, 0.0, HEAD])
    points["head"] = points["neck"] + np.array([0.0, 0.0, NECK - HEAD]) + head
    # Stand the figure on its feet: undo the feet's mean tilt, then put the lower sole on the ground.
    pitch = float(np.mean([np.arctan2(-f[2, 0], f[0, 0]) for f in (r_foot, l_foot)]))
    roll = float(np.mean([np.arctan2(f[2, 1], f[2, 2]) for f in (r_foot, l_foot)]))
    upright = np.linalg.inv(_ry(pitch) @ _rx(roll))
    turned = {name: upright @ p for name, p in points.items()}
    ground = min(turned["r_sole"][2], turned["l_sole"][2])
    return Figure({name: p - np.array([0.0, 0.0, ground]) for name, p in turned.items()})
