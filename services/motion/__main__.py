"""`python -m services.motion`: run the motion service (the OP2's Dynamixel bus, real or simulated).

Environment: HRI_MOTION_PORT (serial device, default /dev/ttyUSB0), HRI_MOTION_SIM (1: start and
drive the simulated OP2 bus; the default when HRI_MOTION_PORT is unset and /dev/ttyUSB0 does not
exist). Command-line options win over the environment.
"""

from __future__ import annotations

import json
from functools import partial
from typing import Annotated, Any

import typer

from services.motion.config import MotionConfigError, MotionSettings
from services.motion.driver import BusError, JointsMissing, Op2Bus
from services.motion.executor import classify
from services.motion.joints import JOINTS, describe
from services.motion.service import NAME, serve
from services.motion.simproc import SimProcess
from services.runtime import get_logger, run_service
from services.runtime.cli import ConnectOption, RobotOption

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    robot: RobotOption = None,
    connect: ConnectOption = None,
    port: Annotated[str | None, typer.Option(help="Serial device of the robot [env HRI_MOTION_PORT]")] = None,
    sim: Annotated[
        bool | None, typer.Option("--sim/--no-sim", help="Drive the simulated OP2 bus [env HRI_MOTION_SIM]")
    ] = None,
    goal_max_age: Annotated[float, typer.Option(help="Drop goals older than this, seconds")] = 1.0,
    renew_timeout: Annotated[
        float, typer.Option(help="Stop walking without a renewal for this long, s")
    ] = 2.0,
    stride: Annotated[
        float, typer.Option(help="Walking stride (forward foot excursion per step), mm")
    ] = 15.0,
    latency_ms: Annotated[float, typer.Option(help="USB latency allowance in reply timeouts, ms")] = 16.0,
) -> None:
    """Run the motion service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    try:
        settings = MotionSettings.resolve(
            port=port,
            sim=sim,
            goal_max_age_s=goal_max_age,
            renew_timeout_s=renew_timeout,
            stride_mm=stride,
            latency_ms=latency_ms,
        )
    except MotionConfigError as exc:
        get_logger(NAME).error("configuration error", error=str(exc))
        raise typer.Exit(2) from None
    raise typer.Exit(run_service(NAME, partial(serve, settings=settings), robot=robot, connect=connect))


@app.command()
def check(
    port: Annotated[str | None, typer.Option(help="Serial device [env HRI_MOTION_PORT]")] = None,
    sim: Annotated[bool | None, typer.Option("--sim/--no-sim", help="Check a fresh simulated bus")] = None,
) -> None:
    """Power the servos, ping the CM-740 and all twenty joints, read positions; print JSON.

    Exit code 0 when every device answers, 1 when some do not, 2 when the port cannot be used.
    Torque is left as it was (off after power-up).
    """
    log = get_logger(NAME)
    try:
        settings = MotionSettings.resolve(port=port, sim=sim)
    except MotionConfigError as exc:
        log.error("configuration error", error=str(exc))
        raise typer.Exit(2) from None
    simulator = SimProcess(log) if settings.sim else None
    report: dict[str, Any] = {"sim": settings.sim}
    code = 0
    try:
        device = simulator.port() if simulator is not None else settings.port
        report["port"] = device
        bus = Op2Bus(device, latency_ms=settings.latency_ms)
        try:
            bus.open()
            bus.power_on()
            missing: list[int] = []
            try:
                bus.check_joints()
            except JointsMissing as exc:
                missing = exc.missing
                report["error"] = str(exc)
                code = 1
            report["missing"] = [describe(i) for i in missing]
            answering = tuple(j for j in JOINTS if j not in missing)
            positions = bus.read_positions(answering)
            report["positions"] = {JOINTS[j].name: v for j, v in positions.items()}
            report["posture"] = classify(positions).value if code == 0 else "unknown"
        finally:
            bus.close()
    except BusError as exc:
        report["error"] = str(exc)
        code = 2
    finally:
        if simulator is not None:
            simulator.stop()
    typer.echo(json.dumps(report, indent=2))
    raise typer.Exit(code)


if __name__ == "__main__":
    app()
