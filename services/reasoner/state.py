"""What the reasoner keeps across restarts (DESIGN.md invariant 4), written atomically.

The file is `<state dir>/reasoner.json`. The state dir is `HRI_STATE_DIR`, or
`$XDG_STATE_HOME/hri/<robot>` (XDG_STATE_HOME defaults to `~/.local/state`).
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from schemas.messages import Situation
from services.reasoner.agent_host import Memory

STATE_FILE = "reasoner.json"


class PersistedState(BaseModel):
    """The on-disk format (a boundary: validated when read)."""

    situation: Situation
    resume_go: bool = False
    resume_asks: bool = False
    saved_at: float = 0.0


class StateStore:
    """Loads and saves `Memory`. A state file that exists but cannot be read is taken as danger:
    the reasoner cannot know whether a danger was latched, so it assumes one (fail safe)."""

    def __init__(self, directory: Path, log: Any) -> None:
        self.directory = directory
        self.path = directory / STATE_FILE
        self.log = log
        self.saved_at: float | None = None
        """When the state that `load()` restored was saved (None: nothing restored)."""

    def load(self) -> Memory:
        try:
            raw = self.path.read_bytes()
        except FileNotFoundError:
            self.log.info("no saved state, starting safe", path=str(self.path))
            return Memory()
        except OSError as exc:
            self.log.error("saved state unreadable, assuming danger", path=str(self.path), error=str(exc))
            return Memory(situation=Situation.DANGER.value)
        try:
            state = PersistedState.model_validate_json(raw)
        except ValidationError as exc:
            self.log.error("saved state invalid, assuming danger", path=str(self.path),
                           error=str(exc).splitlines()[0])
            return Memory(situation=Situation.DANGER.value)
        # logged once by the service, with the episodic memory, when the agent is ready
        self.saved_at = state.saved_at
        return Memory(situation=state.situation.value, resume_go=state.resume_go,
                      resume_asks=state.resume_go and state.resume_asks)

    def save(self, memory: Memory) -> None:
        """Write to a temporary file in the same directory, fsync, then os.replace (atomic)."""
        self.directory.mkdir(parents=True, exist_ok=True)
        state = PersistedState(situation=Situation(memory.situation), resume_go=memory.resume_go,
                               resume_asks=memory.resume_asks, saved_at=time.time())
        fd, tmp = tempfile.mkstemp(prefix=".reasoner-", suffix=".tmp", dir=self.directory)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(json.dumps(state.model_dump(mode="json")))
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, self.path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        dir_fd = os.open(self.directory, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
