"""A whole simulated robot in one folder: the embedded router and the five services under the
launcher (motion on the simulated bus, vision on the synthetic scene, voice listening to a spool
folder, speech writing WAV files), plus a participant on its bus with a recorder and a scenario
runner. The demo, the system tests and the end-to-end benchmark all drive the robot through this.

Secure by default: the deployment's identities are made in `out/keys` (or taken from `keys_dir`),
the router requires them and applies the generated access rules, and the participant is the
`operator`. `secure=False` runs the open bus (for comparing the cost of security)."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import zenoh

from schemas.keys import Keys
from services.cli import keys as deployment_keys
from services.cli.launcher import Launcher
from services.cli.recorder import Event, Recorder
from services.cli.router import free_port
from services.cli.runner import ScenarioRunner
from services.cli.utterance import DEFAULT_VOICE
from services.runtime import Credentials, ServiceContext, client_config


def simulated_env(out: Path) -> dict[str, str]:
    """Service settings for a robot with no hardware, all of whose files live under `out`."""
    return {
        "HRI_STATE_DIR": str(out / "state"),
        "HRI_SPEECH_OUT": str(out / "speech"),
        "HRI_VISION_SOURCE": "synthetic:none",
        "HRI_VOICE_SOURCE": f"watch:{out / 'spool'}",
        "HRI_MOTION_SIM": "1",
    }


@dataclass
class SimulatedRobot:
    out: Path
    launcher: Launcher
    ctx: ServiceContext
    rec: Recorder
    runner: ScenarioRunner

    @property
    def log_path(self) -> Path:
        return self.out / "services.log"


@contextmanager
def simulated_robot(
    out: Path,
    *,
    robot: str = "op2",
    port: int = 0,
    participant: str = "demo",
    voice: str = DEFAULT_VOICE,
    on_event: Callable[[Event], None] | None = None,
    env: Mapping[str, str] | None = None,
    secure: bool = True,
    keys_dir: Path | None = None,
    identity: str = "operator",
) -> Iterator[SimulatedRobot]:
    """Start the robot (service logs to `out/services.log`); stop everything on exit.

    Readiness is the caller's to wait for (`robot.runner.wait_ready()`), so it can report progress.
    """
    (out / "spool").mkdir(parents=True, exist_ok=True)
    log = (out / "services.log").open("w")
    lock = threading.Lock()

    def sink(name: str, line: str) -> None:
        with lock:
            log.write(f"{name:<8} | {line}\n")
            log.flush()

    credentials = None
    if secure:
        keys_dir = keys_dir or out / "keys"
        if not deployment_keys.exists(keys_dir):
            deployment_keys.init(keys_dir)
        credentials = Credentials.load(keys_dir / identity)
    launcher = Launcher(port=port or free_port(), robot=robot, env={**simulated_env(out), **(env or {})},
                        sink=sink, keys_dir=keys_dir if secure else None)
    ctx: ServiceContext | None = None
    try:
        launcher.start()
        ctx = ServiceContext(participant, zenoh.open(client_config([launcher.endpoint], credentials)), Keys(robot))
        rec = Recorder(ctx, on_event)
        yield SimulatedRobot(out, launcher, ctx, rec, ScenarioRunner(ctx, rec, out / "spool", voice=voice))
    finally:
        if ctx is not None:
            ctx.close()
        launcher.stop()
        with lock:
            log.close()
