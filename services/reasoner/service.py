"""The reasoner service: Zenoh in and out of the Soar agent. Python only moves data here;
every decision is made by the productions in services/reasoner/agent/.

Start-up order: restore the saved situation, start the agent from it and wait until it is
ready, and only then subscribe to marks, commands and motion state.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass
from pathlib import Path

import zenoh

from schemas.messages import (
    Command,
    Decision,
    Explanation,
    HealthStatus,
    MarkObservation,
    MotionGoal,
    MotionState,
    SpeechRequest,
    VoiceCommand,
)
from services.reasoner.agent_host import KNOWLEDGE_FILE, AgentConfig, CommandInput, MarksInput, Memory
from services.reasoner.driver import AgentDriver
from services.reasoner.outputs import OutputBridge
from services.reasoner.state import StateStore
from services.runtime import ServiceContext, default_state_dir

NAME = "reasoner"
EPISODES_FILE = "episodes.db"
"""The episodic-memory store, next to reasoner.json in the state folder."""


def _log_restored(ctx: ServiceContext, store: StateStore, restored: Memory, config: AgentConfig,
                  episodes: int) -> None:
    """One line at start: which state folder, what was restored from it, and how much episodic
    memory. Several checkouts share the default folder, so a latched danger may come from another
    one: that case is a warning, so it shows at any log level."""
    saved = (time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(store.saved_at))
             if store.saved_at is not None else None)
    resume = restored.resume_value
    what = (f"situation {restored.situation}, resume_go {resume}, saved {saved}"
            if saved is not None else f"nothing saved: starting {restored.situation}")
    line = f"state restored from {store.path}: {what}; {episodes} episodes in {config.episodes}"
    log = ctx.log.warning if restored.situation == "danger" else ctx.log.info
    log(line, state_file=str(store.path), situation=restored.situation, resume_go=resume,
        saved_at=store.saved_at, episodes=episodes, debugger_port=config.debugger_port)

# Flood limits, the second line behind the router's per-session rate limits (schemas.access
# RATE_LIMITS) and the one that holds on routers configured without them. Marks and commands wait
# in bounded queues (the runtime drops the oldest beyond INPUT_QUEUE), are handed to the agent only
# while fewer than *_BACKLOG inputs wait for it, and commands at most COMMAND_RATE a second; the rest
# are dropped and counted in health `dropped`.
# A publisher flooding commands can neither grow the reasoner's memory, nor queue work in front of
# an X, nor keep the agent (and the process's Python threads) too busy to read the next mark.
# Marks get more room than commands, so a command flood never crowds out a danger sign.
INPUT_QUEUE = 32
COMMAND_BACKLOG = 16
MARKS_BACKLOG = 64
SWITCH_INTERVAL_S = 0.0005
COMMAND_RATE = 50.0
"""Commands a second the agent is given at most (HRI_REASONER_COMMAND_RATE; 0: no limit). People
give a few a second; a flood beyond this would keep the agent, and with it the process, busy."""


@dataclass(frozen=True)
class ReasonerOptions:
    state_dir: Path | None = None
    knowledge_file: Path | None = None
    debugger_port: int | None = None
    keepalive_s: float = 0.5
    explain_timeout_s: float = 4.0
    episodes_max_mb: float = 64.0
    command_rate: float = COMMAND_RATE

    @classmethod
    def from_env(
        cls,
        *,
        state_dir: Path | None = None,
        knowledge_file: Path | None = None,
        debugger_port: int | None = None,
        episodes_max_mb: float | None = None,
    ) -> ReasonerOptions:
        """Explicit values win over HRI_STATE_DIR / HRI_REASONER_KNOWLEDGE / HRI_SOAR_DEBUGGER_PORT."""
        if debugger_port is None and os.environ.get("HRI_SOAR_DEBUGGER_PORT"):
            raw = os.environ["HRI_SOAR_DEBUGGER_PORT"]
            if not raw.isdigit() or not 0 < int(raw) < 65536:
                raise ValueError(f"HRI_SOAR_DEBUGGER_PORT={raw!r} is not a TCP port (1-65535)")
            debugger_port = int(raw)
        if knowledge_file is None and os.environ.get("HRI_REASONER_KNOWLEDGE"):
            knowledge_file = Path(os.environ["HRI_REASONER_KNOWLEDGE"])
        if episodes_max_mb is None and os.environ.get("HRI_REASONER_EPISODES_MAX_MB"):
            raw = os.environ["HRI_REASONER_EPISODES_MAX_MB"]
            try:
                episodes_max_mb = float(raw)
            except ValueError:
                raise ValueError(f"HRI_REASONER_EPISODES_MAX_MB={raw!r} is not a number") from None
        if episodes_max_mb is not None and not episodes_max_mb > 0:
            raise ValueError(f"the episodic-memory bound must be positive, not {episodes_max_mb:g} MB")
        raw_rate = os.environ.get("HRI_REASONER_COMMAND_RATE", str(COMMAND_RATE))
        try:
            command_rate = float(raw_rate)
        except ValueError:
            command_rate = -1.0
        if command_rate < 0:
            raise ValueError(f"HRI_REASONER_COMMAND_RATE={raw_rate!r} is not a rate "
                             "(commands a second, 0: no limit)")
        return cls(state_dir=state_dir, knowledge_file=knowledge_file, debugger_port=debugger_port,
                   command_rate=command_rate,
                   **({"episodes_max_mb": episodes_max_mb} if episodes_max_mb is not None else {}))


def serve(ctx: ServiceContext, options: ReasonerOptions | None = None) -> None:
    options = options or ReasonerOptions.from_env()
    # Under a flood the subscription workers are busy in Python; a shorter GIL switch interval (5 ms
    # by default) lets Zenoh's reading thread in sooner, so the link keeps moving and an X gets through.
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    ctx.update_detail(ready=False)  # until the agent is restored and every subscription declared
    keys = ctx.keys
    store = StateStore(options.state_dir or default_state_dir(ctx.robot), ctx.log)
    memory = store.load()

    bridge = OutputBridge(
        ctx,
        ctx.publisher(keys.motion_goal, MotionGoal, block=True, priority=zenoh.Priority.REAL_TIME),
        ctx.publisher(keys.speech_say, SpeechRequest),
        # above commands, so a command flood does not crowd a decision off a watcher's link
        ctx.publisher(keys.reasoner_decision, Decision, priority=zenoh.Priority.INTERACTIVE_HIGH),
        store,
        keepalive_s=options.keepalive_s,
    )
    config = AgentConfig(knowledge_file=options.knowledge_file or KNOWLEDGE_FILE,
                         debugger_port=options.debugger_port, episodes=store.directory / EPISODES_FILE,
                         episodes_max_bytes=int(options.episodes_max_mb * 1024 * 1024))
    driver = AgentDriver(config, memory, bridge, ctx.log)
    ctx.on_close(driver.stop)
    restored = driver.start()
    ctx.update_detail(state_file=str(store.path), debugger_port=options.debugger_port,
                      knowledge=str(config.knowledge_file), episodes_file=str(config.episodes))
    _log_restored(ctx, store, restored, config, driver.episodes())

    def on_command(msg: VoiceCommand) -> None:
        if driver.backlog() >= COMMAND_BACKLOG:
            ctx.count_drop(keys.voice_command)
            return
        driver.submit(CommandInput.of(msg))

    def on_marks(msg: MarkObservation) -> None:
        # No mark carries no news (DESIGN.md); only observations with marks reach the agent.
        if msg.marks:
            if driver.backlog() >= MARKS_BACKLOG:
                ctx.count_drop(keys.vision_marks)
                return
            driver.submit(MarksInput(shapes=frozenset(m.shape.value for m in msg.marks), stamp=msg.stamp))

    def on_motion(msg: MotionState) -> None:
        driver.set_posture(msg.posture.value)

    def on_explain(_params: str, _payload: bytes) -> Explanation:
        # Asked over the bus, "why" is the same as spoken: the agent answers it (and says it).
        waiting: list[tuple[int, Future[Explanation]]] = []
        driver.submit(CommandInput(word=Command.WHY.value, confidence=1.0, stamp=time.time()),
                      reserve=lambda cause: waiting.append((cause, bridge.expect_explanation(cause))))
        cause, future = waiting[0]
        try:
            return future.result(options.explain_timeout_s)
        except FutureTimeout:
            bridge.forget_explanation(cause)
            raise RuntimeError(
                f"the agent gave no explanation within {options.explain_timeout_s:g} s") from None

    def on_soar(_params: str, payload: bytes) -> str:
        ok, out = driver.run_command(payload.decode("utf-8", "replace"))
        if not ok:
            raise RuntimeError(out.strip() or "Soar command failed")
        return out

    ctx.subscribe(keys.motion_state, MotionState, on_motion)
    ctx.subscribe(keys.vision_marks, MarkObservation, on_marks, queue=INPUT_QUEUE,
                  when=lambda: driver.backlog() < MARKS_BACKLOG)
    ctx.subscribe(keys.voice_command, VoiceCommand, on_command, queue=INPUT_QUEUE,
                  when=lambda: driver.backlog() < COMMAND_BACKLOG, rate=options.command_rate or None)
    ctx.queryable(keys.reasoner_soar, on_soar)
    ctx.queryable(keys.reasoner_explain, on_explain)
    ctx.thread(lambda: bridge.run_keepalive(driver.responsive), "walk-keepalive")
    ctx.update_detail(ready=True)  # every subscription is declared: inputs are accepted now

    while not ctx.wait(0.5):
        if not driver.is_alive():
            ctx.set_status(HealthStatus.FAILED, error="the Soar driver thread ended")
            raise RuntimeError("the Soar driver thread ended; see the log above")
        ctx.update_detail(backlog=driver.backlog(), **driver.stats(), **bridge.detail())
