"""Open-loop walking gait in the style of the ROBOTIS OP2 framework, with leg inverse kinematics.

The robot steps in place or forward with a period of 600 ms: each half period one foot swings
(single support) while the other carries the body; around each half-period boundary both feet are
on the ground (double support). Foot trajectories are sinusoids (`wsin`), the body sways sideways
over the stance foot and bobs vertically, arms swing against the legs. Stride changes happen only
at half-period boundaries: a stop request makes the next step close the feet together, and the gait
ends at the following boundary, in double support.

Parameters and conventions (joint directions, offsets) follow REFERENCE.md and the ROBOTIS
framework; lengths in mm, angles in degrees, time in seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from services.motion.joints import ARMS, CENTER, TICKS_PER_DEGREE, Pose

THIGH = 93.0
CALF = 93.0
ANKLE = 33.5
LEG = THIGH + CALF + ANKLE

# joint ids of each leg, in IK output order: hip yaw, hip roll, hip pitch, knee, ankle pitch, ankle roll
RIGHT_LEG = (7, 9, 11, 13, 15, 17)
LEFT_LEG = (8, 10, 12, 14, 16, 18)
# sign of each IK angle on the servo, per leg (ROBOTIS joint directions)
RIGHT_DIR = (-1, -1, 1, 1, -1, 1)
LEFT_DIR = (-1, -1, -1, -1, 1, 1)
R_ARM_PITCH, L_ARM_PITCH = 1, 2


def wsin(t: float, period: float, phase: float, amplitude: float, shift: float) -> float:
    """The framework's base waveform: amplitude * sin(2 pi t / period - phase) + shift."""
    return amplitude * math.sin(2.0 * math.pi * t / period - phase) + shift


@dataclass(frozen=True)
class GaitParams:
    period: float = 0.600
    dsp_ratio: float = 0.1
    step_fb_ratio: float = 0.28
    foot_height: float = 40.0
    swing_y: float = 20.0
    swing_z: float = 5.0
    x_offset: float = -10.0
    y_offset: float = 5.0
    z_offset: float = 20.0
    hip_pitch_offset: float = 13.0
    arm_swing_gain: float = 1.5
    pelvis_offset: float = 3.0
    stride: float = 15.0
    """Forward foot excursion per step (the framework's X move amplitude), mm."""
    dt: float = 0.008

    @property
    def half(self) -> float:
        return self.period / 2.0

    @property
    def ssp_window(self) -> tuple[float, float]:
        """Single-support window inside each half period (start, end), seconds."""
        edge = self.dsp_ratio * self.period / 4.0
        return edge, self.half - edge


@dataclass(frozen=True)
class LegAngles:
    """IK result in degrees: hip yaw, hip roll, hip pitch, knee, ankle pitch, ankle roll."""

    values: tuple[float, float, float, float, float, float]


def leg_ik(x: float, y: float, z: float) -> LegAngles | None:
    """Joint angles that put the foot (kept flat, pointing forward) at (x, y, z) from its neutral
    position under the hip; z > 0 shortens the leg. None when out of reach."""
    ax, ay, az = x, y, z - LEG + ANKLE  # ankle joint relative to the hip joint
    reach = math.sqrt(ax * ax + ay * ay + az * az)
    cos_knee = (reach * reach - THIGH * THIGH - CALF * CALF) / (2.0 * THIGH * CALF)
    if not -1.0 <= cos_knee <= 1.0:
        return None
    knee = math.acos(cos_knee)
    height = LEG - ANKLE - z
    if height <= 0:
        return None
    hip_roll = math.atan2(y, height)
    ankle_roll = -hip_roll
    k = math.sin(knee) * CALF
    ll = -THIGH - math.cos(knee) * CALF
    m = ax
    n = math.cos(hip_roll) * az - math.sin(hip_roll) * ay
    s = (k * n + ll * m) / (k * k + ll * ll)
    c = (n - k * s) / ll
    hip_pitch = math.atan2(s, c)
    ankle_pitch = -knee - hip_pitch
    return LegAngles(
        tuple(math.degrees(a) for a in (0.0, hip_roll, hip_pitch, knee, ankle_pitch, ankle_roll))  # type: ignore[arg-type]
    )


@dataclass
class GaitFrame:
    """One tick of the gait: joint targets plus what the feet are doing (for tests and state)."""

    pose: Pose
    left_lift: float
    right_lift: float
    left_x: float
    right_x: float
    double_support: bool


@dataclass
class Gait:
    """Steps until stopped. Call `next()` once per control tick; it returns None once finished."""

    params: GaitParams = field(default_factory=GaitParams)
    time: float = 0.0
    """Time inside the current period, a multiple of dt."""
    stride: float = 0.0
    """Stride of the step in progress (feet end at +stride / -stride)."""
    stop_requested: bool = False
    finished: bool = False
    steps: int = 0
    _x_left: float = 0.0
    _x_right: float = 0.0
    _from_left: float = 0.0
    _from_right: float = 0.0
    _last_pose: Pose | None = None

    def __post_init__(self) -> None:
        self._begin_step()

    def request_stop(self) -> None:
        self.stop_requested = True

    def resume(self) -> bool:
        """Cancel a pending stop; False when the gait has already ended."""
        if self.finished:
            return False
        self.stop_requested = False
        return True

    @property
    def left_swings(self) -> bool:
        return self.time < self.params.half

    def _begin_step(self) -> None:
        """At a half-period boundary: choose the next step's stride, or end the gait."""
        feet_together = abs(self._x_left) < 1e-9 and abs(self._x_right) < 1e-9
        if self.stop_requested and feet_together and self.steps > 0:
            self.finished = True
            return
        self.stride = 0.0 if self.stop_requested else self.params.stride
        self._from_left, self._from_right = self._x_left, self._x_right
        self.steps += 1

    def next(self) -> GaitFrame | None:
        if self.finished:
            return None
        frame = self.frame()
        p = self.params
        boundary_before = self.time < p.half
        self.time = round(self.time + p.dt, 9)
        if self.time >= p.period - 1e-9:
            self.time = 0.0
        if boundary_before != (self.time < p.half):
            self.time = min(p.half, self.time)  # the half period is not a whole number of ticks: snap to it
            self._x_left, self._x_right = self._end_positions()
            self._begin_step()
        return frame

    def _end_positions(self) -> tuple[float, float]:
        """Where the feet are at the end of the step just finished (swing foot ahead)."""
        left_swung = self.time >= self.params.half  # we just crossed into the right's half
        return (self.stride, -self.stride) if left_swung else (-self.stride, self.stride)

    def frame(self) -> GaitFrame:
        p = self.params
        t = self.time
        left_swing = t < p.half
        tau = t if left_swing else t - p.half
        start, end = p.ssp_window
        progress = min(max((tau - start) / (end - start), 0.0), 1.0)
        ease = (1.0 - math.cos(math.pi * progress)) / 2.0
        bump = (1.0 - math.cos(2.0 * math.pi * progress)) / 2.0
        swing_to, stance_to = self.stride, -self.stride
        if left_swing:
            x_left = self._from_left + (swing_to - self._from_left) * ease
            x_right = self._from_right + (stance_to - self._from_right) * ease
            lift_left, lift_right = p.foot_height * bump, 0.0
        else:
            x_right = self._from_right + (swing_to - self._from_right) * ease
            x_left = self._from_left + (stance_to - self._from_left) * ease
            lift_left, lift_right = 0.0, p.foot_height * bump
        x_swap = wsin(t, p.half, math.pi, self.stride * p.step_fb_ratio, 0.0)
        y_swap = wsin(t, p.period, 0.0, p.swing_y, 0.0)
        z_swap = wsin(t, p.half, 1.5 * math.pi, p.swing_z, p.swing_z)
        right = leg_ik(
            x_swap + x_right + p.x_offset, y_swap - p.y_offset / 2, z_swap + lift_right + p.z_offset
        )
        left = leg_ik(x_swap + x_left + p.x_offset, y_swap + p.y_offset / 2, z_swap + lift_left + p.z_offset)
        if right is None or left is None:  # unreachable: hold the last pose (never with default parameters)
            pose = dict(self._last_pose) if self._last_pose else {}
        else:
            pelvis = p.pelvis_offset * bump
            roll_left = pelvis * (0.35 if left_swing else 1.0)
            roll_right = -pelvis * (1.0 if left_swing else 0.35)
            pose = {}
            self._put_leg(pose, RIGHT_LEG, RIGHT_DIR, right, roll_right)
            self._put_leg(pose, LEFT_LEG, LEFT_DIR, left, roll_left)
            arm = p.arm_swing_gain
            pose[R_ARM_PITCH] = ARMS[R_ARM_PITCH] + (-arm * x_right) * TICKS_PER_DEGREE
            pose[L_ARM_PITCH] = ARMS[L_ARM_PITCH] - (-arm * x_left) * TICKS_PER_DEGREE
            for jid in (3, 4, 5, 6):
                pose[jid] = ARMS[jid]
            self._last_pose = pose
        return GaitFrame(
            pose=pose,
            left_lift=lift_left,
            right_lift=lift_right,
            left_x=x_left,
            right_x=x_right,
            double_support=lift_left == 0.0 and lift_right == 0.0,
        )

    def _put_leg(
        self, pose: Pose, ids: tuple[int, ...], dirs: tuple[int, ...], angles: LegAngles, pelvis_roll: float
    ) -> None:
        for i, (jid, sign) in enumerate(zip(ids, dirs, strict=True)):
            angle = angles.values[i]
            if i == 1:
                angle += pelvis_roll
            offset = sign * angle * TICKS_PER_DEGREE
            if i == 2:
                offset -= sign * self.params.hip_pitch_offset * TICKS_PER_DEGREE
            pose[jid] = CENTER + offset


def ready_pose(params: GaitParams | None = None) -> Pose:
    """The gait's standing pose (feet together, the first frame of a walk and the last of a stop)."""
    return Gait(params or GaitParams()).frame().pose
