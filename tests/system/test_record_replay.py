"""A session of the whole robot recorded to MCAP, read back with the `mcap` reader, and replayed into
a fresh robot, which must make the same decisions."""

from __future__ import annotations

import json
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import jsonschema
import pytest
from mcap.reader import make_reader

from schemas.messages import MODELS, Decision
from services.cli import replay as rp
from services.cli.mcapfile import Recorded, read_recording
from services.cli.record import McapRecorder, RecordSummary
from services.cli.scenario import Scenario
from services.cli.simrobot import simulated_robot

pytestmark = pytest.mark.system

# Replay reproduces the inputs' timing, not the motion's: the waits leave a margin after a motion ends
# before a command whose decision depends on it having ended (the motion's own duration varies with
# the machine's load).
STEPS = [
    {"say": "stand", "expect": {"verdict": "obey", "action": "stand_up", "posture": "standing"}},
    {"show": "X", "expect": {"situation": "danger"}},
    {"send": "go", "expect": {"verdict": "refuse", "reason": "danger_sign", "no_action": True}},
    {"show": "O", "expect": {"situation": "safe", "action": "walk_forward", "posture": "walking"}},
    {"send": "stop", "expect": {"verdict": "obey", "posture": "standing"}},
    {"wait": 1.0},
    {"send": "down", "expect": {"verdict": "obey", "posture": "sitting"}},
    {"wait": 1.0},
    {"send": "down", "expect": {"verdict": "ignore", "reason": "already_done"}},
]


@dataclass
class Session:
    path: Path
    robot: str
    summary: RecordSummary


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    """The scenario played on a simulated robot while `McapRecorder` records everything."""
    out = tmp_path_factory.mktemp("recorded")
    robot = f"t{uuid.uuid4().hex[:10]}"
    path = out / "session.mcap"
    with simulated_robot(out, robot=robot, participant="systest") as sim:
        missing = sim.runner.wait_ready(timeout=90)
        assert not missing, f"robot did not come up: {missing}; see {sim.log_path}"
        recorder = McapRecorder(sim.ctx, path)
        try:
            results = sim.runner.run(Scenario.model_validate({"name": "recorded", "steps": STEPS}))
        finally:
            summary = recorder.close()
        failed = [f"step {r.index} {r.step.label()}: {'; '.join(r.problems)}" for r in results if not r.ok]
        assert not failed, "\n".join(failed)
    yield Session(path, robot, summary)


def test_the_recording_reads_back_with_valid_schemas_and_messages(session: Session) -> None:
    prefix = f"hri/{session.robot}"
    with session.path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        topics = {c.topic for c in summary.channels.values()}
        for topic in ("vision/marks", "vision/scene", "vision/preview", "voice/command", "reasoner/decision",
                      "motion/goal", "motion/state", "motion/joints", "speech/say", "speech/state"):
            assert f"{prefix}/{topic}" in topics, sorted(topics)
        validators = {}
        for schema in summary.schemas.values():
            assert schema.encoding == "jsonschema" and schema.name in MODELS
            doc = json.loads(schema.data)
            jsonschema.Draft202012Validator.check_schema(doc)  # a valid JSON Schema ...
            assert doc == MODELS[schema.name].model_json_schema()  # ... and the model's own
            validators[schema.id] = jsonschema.Draft202012Validator(doc)
        assert all(c.message_encoding == "json" for c in summary.channels.values())
        n = 0
        for schema, _channel, message in reader.iter_messages():
            payload = json.loads(message.data)
            validators[schema.id].validate(payload)
            msg = MODELS[schema.name].model_validate(payload)
            assert message.log_time == int(msg.stamp * 1e9) and message.sequence == msg.seq
            n += 1
    assert n == summary.statistics.message_count == session.summary.messages
    assert set(session.summary.counts) == topics
    assert session.summary.size_bytes == session.path.stat().st_size > 0
    assert not session.summary.rejected


def test_replaying_the_inputs_into_a_fresh_robot_gives_the_same_decisions(session: Session,
                                                                         tmp_path: Path) -> None:
    recorded: list[Recorded] = list(read_recording(session.path))
    expected = rp.recorded_decisions(recorded)
    assert [rp.signature(d)[:3] for d in expected if d.command] == [
        ("stand", "obey", "ok"), ("go", "refuse", "danger_sign"), ("stop", "obey", "ok"),
        ("down", "obey", "ok"), ("down", "ignore", "already_done")]
    inputs = rp.select(recorded)
    assert {rp.topic_of(m.key) for m in inputs} == {"vision/marks", "voice/command"}
    with simulated_robot(tmp_path, robot=f"t{uuid.uuid4().hex[:10]}", participant="systest") as sim:
        missing = sim.runner.wait_ready(timeout=90)
        assert not missing, f"robot did not come up: {missing}; see {sim.log_path}"
        watch = rp.DecisionWatch(sim.ctx)
        result = rp.Replayer(sim.ctx, inputs).run()
        assert result.published == len(inputs) and not result.unmatched
        span = inputs[-1].log_time - inputs[0].log_time
        assert span <= result.seconds < span + 2.0
        got = watch.settle(len(expected), quiet_s=2.0, timeout=30.0)
    assert rp.compare(expected, got) == []


def test_compare_names_each_difference() -> None:
    def d(command: str | None, verdict: str, reason: str, situation: str = "safe") -> Decision:
        return Decision(command=command, verdict=verdict, reason=reason, situation=situation)

    a = [d("go", "refuse", "danger_sign", "danger"), d("stand", "obey", "ok")]
    assert rp.compare(a, a) == []
    diff = rp.compare(a, [d("go", "obey", "ok", "danger")])
    assert diff == ["decision 1: recorded go -> refuse danger_sign, action -, danger, replayed go -> obey ok, "
                    "action -, danger", "decision 2: recorded stand -> obey ok, action -, safe, replayed nothing"]
