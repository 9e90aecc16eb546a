"""Present joint positions on the bus (`JointPositions` on `hri/<robot>/motion/joints`), for viewers.

The control loop already reads every joint's present position each 8 ms tick (one BULK_READ); this
publishes the latest of those readings at `RATE_HZ`, while the bus is working and only while
someone subscribes (Zenoh's matching status): nothing is encoded for nobody.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping

from schemas.messages import JointPositions
from services.motion.joints import CENTER, JOINTS
from services.runtime import ServiceContext

RATE_HZ = 25.0
RADIANS_PER_TICK = 2 * math.pi / 4096


def joint_positions(present: Mapping[int, int], stamp: float | None = None) -> JointPositions:
    """Ticks by Dynamixel id -> the message: ids in order, names, ticks and radians from the centre."""
    ids = sorted(present)
    return JointPositions(
        stamp=time.time() if stamp is None else stamp,
        ids=ids,
        names=[JOINTS[i].name if i in JOINTS else f"id{i}" for i in ids],
        ticks=[present[i] for i in ids],
        radians=[round((present[i] - CENTER) * RADIANS_PER_TICK, 5) for i in ids],
    )


def publish_joints(ctx: ServiceContext, read: Callable[[], Mapping[int, int]], rate_hz: float = RATE_HZ) -> None:
    """Publish `read()` (ticks by id; empty while the bus is down) every 1/`rate_hz` s until stopped."""
    pub = ctx.publisher(ctx.keys.motion_joints, JointPositions)
    period = 1.0 / rate_hz
    due = time.monotonic()
    while True:
        due += period
        now = time.monotonic()
        if due < now:  # fell behind (a loaded machine): keep the pace, do not burst
            due = now
        if ctx.wait(due - now):
            return
        if not pub.matched:
            continue
        present = dict(read())
        if present:
            pub.put(joint_positions(present))
