"""The motion service: MotionGoal in, MotionState out, the OP2 (real or simulated) in between.

Zenoh wiring and safety watchdogs around the control loop (services/motion/loop.py):
- goals older than `goal_max_age_s` are dropped and logged, except a stop, which is carried out late rather
  than never (stopping is the safe direction, and a clock that jumped must not cancel it);
- walking stops when the reasoner's liveliness token goes (at once: the gait then ends at its
  next half-cycle boundary) or when the walk goal is not renewed within `renew_timeout_s`;
- MotionState on every change and at least every `state_period_s`.
"""

from __future__ import annotations

import time
from typing import Any

from schemas.messages import Action, HealthStatus, MotionGoal, MotionState
from services.motion.config import MotionSettings
from services.motion.executor import GoalRequest, Snapshot
from services.motion.loop import ControlLoop
from services.motion.present import publish_joints
from services.motion.simproc import SimProcess
from services.runtime import ServiceContext

NAME = "motion"


def serve(ctx: ServiceContext, settings: MotionSettings | None = None) -> None:
    settings = settings or MotionSettings.resolve()
    state_pub = ctx.publisher(ctx.keys.motion_state, MotionState)
    sim = SimProcess(ctx.log) if settings.sim else None
    last_publish = [0.0]
    stale, late_stops = [0], [0]

    def publish(snap: Snapshot, bus_ok: bool) -> None:
        last_publish[0] = time.monotonic()
        state_pub.put(
            MotionState(
                posture=snap.posture,
                action=snap.action,
                goal_id=snap.goal_id,
                bus_ok=bus_ok,
                goal_stamp=snap.goal_stamp,
                first_write=snap.first_write,
            )
        )

    def health(status: HealthStatus | None, **detail: Any) -> None:
        if status is None:
            ctx.update_detail(**detail)
        else:
            ctx.set_status(status, **detail)

    def port() -> str:
        if sim is None:
            return settings.port
        path = sim.port()
        ctx.update_detail(sim_pid=sim.pid)
        return path

    loop = ControlLoop(settings, log=ctx.log, port=port, publish=publish, health=health)
    ctx.update_detail(
        sim=settings.sim,
        device=None if settings.sim else settings.port,
        goal_max_age_s=settings.goal_max_age_s,
        renew_timeout_s=settings.renew_timeout_s,
    )

    def on_goal(goal: MotionGoal) -> None:
        received = time.time()
        age = received - goal.stamp
        if age > settings.goal_max_age_s and goal.action == Action.STOP:
            # A stop is never dropped for its stamp: carried out late it is harmless (the reasoner's later goals come
            # after it); dropped, it would leave the walk to the renewal watchdog. Stamps look late when the clocks of
            # the reasoner's and the robot's machines disagree, or when the robot's clock steps at its first NTP sync.
            late_stops[0] += 1
            ctx.update_detail(late_stops=late_stops[0])
            ctx.log.warning("late stop goal carried out", goal_id=goal.goal_id, age_s=round(age, 3),
                            max_age_s=settings.goal_max_age_s)
        elif age > settings.goal_max_age_s:
            stale[0] += 1
            ctx.update_detail(stale_goals=stale[0])
            ctx.log.warning(
                "stale goal dropped",
                action=goal.action.value,
                goal_id=goal.goal_id,
                age_s=round(age, 3),
                max_age_s=settings.goal_max_age_s,
            )
            return
        loop.submit(GoalRequest(goal.action, goal.goal_id, goal.stamp, received))

    def on_reasoner(key: str, alive: bool) -> None:
        ctx.log.info("reasoner liveliness", key=key, alive=alive)
        if not alive:
            loop.reasoner_lost()

    ctx.subscribe(ctx.keys.motion_goal, MotionGoal, on_goal)
    ctx.thread(lambda: publish_joints(ctx, lambda: loop.present if loop.bus_ok else {}), "joints")
    ctx.on_liveliness(ctx.keys.alive("reasoner"), on_reasoner)
    control = ctx.thread(loop.run, "control")
    try:
        while not ctx.wait(settings.state_period_s / 3):
            if loop.attempted.is_set() and time.monotonic() - last_publish[0] >= settings.state_period_s:
                publish(*loop.snapshot())
    finally:
        loop.stop()
        control.join(5.0)
        if sim is not None:
            sim.stop()
