"""A whole robot per test: embedded router, the five services as real processes under the launcher
(motion on the simulated bus, vision on the synthetic scene, voice on a spool folder, speech to WAV
files), plus a recorder and a scenario runner on the same bus."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from schemas import Health, MotionState, Posture
from schemas.keys import SERVICES
from services.cli.scenario import Scenario
from services.cli.simrobot import SimulatedRobot, simulated_robot
from services.runtime import Credentials, client_config

HERE = Path(__file__).parent


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Every test in this folder is a system test (`-m system`, `-m 'not system'`): a `pytestmark`
    in a conftest marks nothing."""
    for item in items:
        if item.path.is_relative_to(HERE):
            item.add_marker(pytest.mark.system)


class Robot(SimulatedRobot):
    """The simulated robot with what the system tests ask of it."""

    def play(self, steps: list[dict]) -> list:
        scenario = Scenario.model_validate({"name": "test", "steps": steps})
        results = self.runner.run(scenario)
        problems = [f"step {r.index} {r.step.label()}: {'; '.join(r.problems)}" for r in results if not r.ok]
        assert not problems, "\n".join(problems) + f"\n(service logs: {self.log_path})"
        return results

    def health(self, service: str) -> Health | None:
        return self.runner.health(service)

    def pids(self) -> dict[str, int | None]:
        return {name: self.launcher.pid(name) for name in SERVICES}

    def session_as(self, identity: str) -> zenoh.Session:
        """A session on the robot's bus as one of its deployment's identities (`out/keys`); close it."""
        return zenoh.open(client_config([self.launcher.endpoint], Credentials.load(self.out / "keys" / identity)))

    def walking_states_since(self, t: float) -> list[MotionState]:
        return [s for s in self.rec.since(t, "motion") if s.posture == Posture.WALKING]


@pytest.fixture
def robot(tmp_path: Path, robot_id: str) -> Iterator[Robot]:
    with simulated_robot(tmp_path, robot=robot_id, participant="systest") as sim:
        missing = sim.runner.wait_ready(timeout=90)
        assert not missing, f"robot did not come up: {missing}; see {sim.log_path}"
        yield Robot(sim.out, sim.launcher, sim.ctx, sim.rec, sim.runner)
