"""The output bridge on a real bus: goal ids, keep-alive, and no renewal from a stuck agent."""

from __future__ import annotations

import threading
from pathlib import Path

import zenoh

from schemas.messages import Decision, MotionGoal, SpeechRequest
from services.reasoner.agent_host import MotionOutput
from services.reasoner.outputs import OutputBridge
from services.reasoner.state import StateStore
from services.runtime import ServiceContext
from tests.conftest import wait_for


def test_renewals_keep_the_goal_id_and_stop_when_unresponsive(bus: ServiceContext, tmp_path: Path) -> None:
    k = bus.keys
    got: list[MotionGoal] = []
    lock = threading.Lock()

    def add(goal: MotionGoal) -> None:
        with lock:
            got.append(goal)

    bus.subscribe(k.motion_goal, MotionGoal, add)
    bridge = OutputBridge(
        bus,
        bus.publisher(k.motion_goal, MotionGoal, block=True, priority=zenoh.Priority.REAL_TIME),
        bus.publisher(k.speech_say, SpeechRequest),
        bus.publisher(k.reasoner_decision, Decision),
        StateStore(tmp_path, bus.log),
    )
    bridge(MotionOutput(action="walk_forward", cause_stamp=12.5, sustain=True))
    assert bridge.renew(responsive=True)
    assert not bridge.renew(responsive=False)  # a stuck agent could not stop for a danger
    wait_for(lambda: len(got) == 2)
    assert got[0].goal_id == got[1].goal_id and got[1].stamp > got[0].stamp
    assert got[1].cause_stamp == 12.5 and got[1].seq > got[0].seq
    bridge(MotionOutput(action="stop", cause_stamp=13.0))
    assert not bridge.renew(responsive=True)  # any other goal ends the keep-alive
    wait_for(lambda: len(got) == 3)
    assert got[2].action == "stop" and got[2].goal_id != got[0].goal_id
    assert bridge.detail()["walk_renewals_withheld"] == 1
