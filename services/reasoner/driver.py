"""The thread that owns the Soar agent: creates it, pumps it when input arrives, runs Soar
commands for the bus between pumps, and shuts the kernel down. No other thread touches SML."""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from services.reasoner.agent_host import AgentConfig, Event, Memory, Output, SoarAgent

FORBIDDEN_COMMANDS = {
    "exit": "would stop the reasoner; stop the service with SIGTERM instead",
    "quit": "would stop the reasoner; stop the service with SIGTERM instead",
    "init": "would forget the latched situation; restart the service instead",
    "init-soar": "would forget the latched situation; restart the service instead",
    "is": "would forget the latched situation; restart the service instead",
    "soar init": "would forget the latched situation; restart the service instead",
}
"""Soar commands (and their aliases in 9.6) refused over the bus, with the reason."""


class AgentDriver:
    def __init__(self, config: AgentConfig, memory: Memory, sink: Callable[[Output], None], log: Any) -> None:
        self._config = config
        self._memory = memory
        self._sink = sink
        self.log = log
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._commands: queue.SimpleQueue[tuple[str, Future[tuple[bool, str]]]] = queue.SimpleQueue()
        self._agent: SoarAgent | None = None
        self._error: BaseException | None = None
        self._busy_since: float | None = None  # monotonic start of the pump in progress
        self._thread = threading.Thread(target=self._run, name="reasoner:soar", daemon=True)

    # ------------------------------------------------------------------ any thread
    def start(self, timeout: float = 30.0) -> Memory:
        """Start the thread and wait until the agent reported ready; raise its load error."""
        self._thread.start()
        if not self._ready.wait(timeout):
            raise RuntimeError(f"the Soar agent was not ready within {timeout} s")
        if self._error is not None:
            raise self._error
        assert self._agent is not None and self._agent.ready is not None
        return self._agent.ready

    def submit(self, event: Event, reserve: Callable[[int], None] | None = None) -> int:
        assert self._agent is not None, "submit before start"
        input_id = self._agent.submit(event, reserve)
        self._wake.set()
        return input_id

    def set_posture(self, posture: str) -> None:
        assert self._agent is not None, "set_posture before start"
        self._agent.set_posture(posture)
        self._wake.set()

    def is_alive(self) -> bool:
        return self._thread.is_alive()

    def responsive(self, within: float = 1.0) -> bool:
        """The agent thread is alive and not stuck: idle, or its last decision cycle ran within
        `within` seconds. A walk keep-alive must stop when this is False."""
        if not self._thread.is_alive() or self._agent is None:
            return False
        busy_since = self._busy_since
        if busy_since is None:
            return True
        return time.monotonic() - max(busy_since, self._agent.last_cycle) < within

    def backlog(self) -> int:
        return self._agent.pending() if self._agent is not None else 0

    def episodes(self) -> int:
        """Episodes in the agent's episodic memory (asked between pumps)."""
        try:
            ok, out = self.run_command("epmem --stats time")
        except Exception:
            return -1
        digits = "".join(ch for ch in out if ch.isdigit())
        return max(0, int(digits) - 1) if ok and digits else -1

    def stats(self) -> dict[str, int]:
        agent = self._agent
        if agent is None:
            return {}
        return {"events_applied": agent.events_applied, "soar_callback_errors": agent.callback_errors,
                "episode_rotations": agent.episode_rotations}

    def run_command(self, command: str, timeout: float = 5.0) -> tuple[bool, str]:
        """Run a Soar command line on the live agent, between pumps."""
        words = command.split()
        if not words:
            raise ValueError("empty Soar command")
        for name in (" ".join(words[:2]), words[0]):
            if name in FORBIDDEN_COMMANDS:
                raise ValueError(f"'{name}' {FORBIDDEN_COMMANDS[name]}")
        future: Future[tuple[bool, str]] = Future()
        self._commands.put((command, future))
        self._wake.set()
        return future.result(timeout)

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(10.0)

    # ------------------------------------------------------------------ the owner thread
    def _run(self) -> None:
        try:
            self._agent = SoarAgent(self._config, self._memory, on_output=self._sink, log=self.log)
        except BaseException as exc:
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        try:
            # with a debugger listener, wake often enough to answer it promptly
            idle_wait = 0.05 if self._config.debugger_port is not None else 1.0
            while not self._stop.is_set():
                # the agent's own timers (a question's timeout) wake the loop too
                timer_in = self._agent.next_timer_in()
                self._wake.wait(idle_wait if timer_in is None else min(idle_wait, timer_in))
                self._wake.clear()
                self._agent.serve_remote()
                self._run_commands()
                if self._agent.fire_timers() or self._agent.pending():
                    self._busy_since = time.monotonic()
                    try:
                        self._agent.pump()
                    finally:
                        self._busy_since = None
        except Exception:
            self.log.exception("Soar driver failed")
        finally:
            self._agent.close()
            while not self._commands.empty():
                _, future = self._commands.get_nowait()
                future.set_exception(RuntimeError("the reasoner is stopping"))

    def _run_commands(self) -> None:
        assert self._agent is not None
        while not self._commands.empty():
            command, future = self._commands.get_nowait()
            try:
                future.set_result(self._agent.execute(command))
            except Exception as exc:
                future.set_exception(exc)
