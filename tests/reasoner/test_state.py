"""Persistence of the latched situation (DESIGN.md invariant 4)."""

from __future__ import annotations

import json
from pathlib import Path

from services.reasoner.agent_host import Memory
from services.reasoner.state import StateStore
from services.runtime import default_state_dir, get_logger

LOG = get_logger("reasoner-test")


def test_round_trip_leaves_no_temporary_files(tmp_path: Path) -> None:
    store = StateStore(tmp_path / "deep" / "dir", LOG)
    assert store.load() == Memory()  # nothing saved yet: safe
    store.save(Memory("danger", True))
    assert StateStore(tmp_path / "deep" / "dir", LOG).load() == Memory("danger", True)
    store.save(Memory("danger", True, resume_asks=True))
    assert store.load() == Memory("danger", True, resume_asks=True)
    store.save(Memory("safe", False))
    assert store.load() == Memory("safe", False)
    assert [p.name for p in (tmp_path / "deep" / "dir").iterdir()] == ["reasoner.json"]
    assert json.loads(store.path.read_text())["situation"] == "safe"


def test_unreadable_state_fails_safe_to_danger(tmp_path: Path) -> None:
    store = StateStore(tmp_path, LOG)
    store.path.write_text("{truncated")
    assert store.load() == Memory("danger", False)
    store.path.write_text(json.dumps({"situation": "maybe"}))
    assert store.load().situation == "danger"


def test_state_dir_defaults(tmp_path: Path) -> None:
    assert default_state_dir("op2", {"HRI_STATE_DIR": str(tmp_path)}) == tmp_path
    assert default_state_dir("r1", {"XDG_STATE_HOME": "/x"}) == Path("/x/hri/r1")
    assert default_state_dir("r1", {}) == Path.home() / ".local/state/hri/r1"
