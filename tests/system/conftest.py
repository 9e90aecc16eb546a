"""A whole robot per test: embedded router, the five services as real processes under the launcher
(motion on the simulated bus, vision on the synthetic scene, voice on a spool folder, speech to WAV
files), plus a recorder and a scenario runner on the same bus."""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
import zenoh

from schemas import Health, Keys, MotionState, Posture
from schemas.keys import SERVICES
from services.cli.launcher import Launcher
from services.cli.recorder import Recorder
from services.cli.router import free_port
from services.cli.runner import ScenarioRunner
from services.cli.scenario import Scenario
from services.runtime import ServiceContext, client_config, decode

pytestmark = pytest.mark.system


@dataclass
class Robot:
    launcher: Launcher
    ctx: ServiceContext
    rec: Recorder
    runner: ScenarioRunner
    out: Path

    def play(self, steps: list[dict]) -> list:
        scenario = Scenario.model_validate({"name": "test", "steps": steps})
        results = self.runner.run(scenario)
        problems = [f"step {r.index} {r.step.label()}: {'; '.join(r.problems)}" for r in results if not r.ok]
        assert not problems, "\n".join(problems) + f"\n(service logs: {self.out / 'services.log'})"
        return results

    def health(self, service: str) -> Health | None:
        for reply in self.ctx.session.get(self.ctx.keys.health(service), timeout=2.0):
            if reply.ok is not None:
                return decode(reply.ok.payload.to_bytes(), Health)
        return None

    def pids(self) -> dict[str, int | None]:
        return {name: self.launcher.pid(name) for name in SERVICES}

    def walking_states_since(self, t: float) -> list[MotionState]:
        return [s for s in self.rec.since(t, "motion") if s.posture == Posture.WALKING]


@pytest.fixture
def robot(tmp_path: Path, robot_id: str) -> Iterator[Robot]:
    out = tmp_path
    (out / "spool").mkdir()
    env = {
        "HRI_STATE_DIR": str(out / "state"),
        "HRI_SPEECH_OUT": str(out / "speech"),
        "HRI_VISION_SOURCE": "synthetic:none",
        "HRI_VOICE_SOURCE": f"watch:{out / 'spool'}",
        "HRI_MOTION_SIM": "1",
    }
    log = (out / "services.log").open("w")

    def sink(name: str, line: str) -> None:
        log.write(f"{name:<8} | {line}\n")
        log.flush()

    launcher = Launcher(port=free_port(), robot=robot_id, env=env, sink=sink)
    launcher.start()
    ctx = ServiceContext("systest", zenoh.open(client_config([launcher.endpoint])), Keys(robot_id))
    rec = Recorder(ctx)
    runner = ScenarioRunner(ctx, rec, out / "spool")
    try:
        missing = runner.wait_ready(timeout=90)
        assert not missing, f"robot did not come up: {missing}; see {out / 'services.log'}"
        yield Robot(launcher, ctx, rec, runner, out)
    finally:
        ctx.close()
        launcher.stop()
        log.close()
        if os.environ.get("HRI_KEEP_SYSTEM_LOGS"):
            print(json.dumps({"logs": str(out / "services.log")}))
