"""Hosts the Soar kernel and the HRI agent behind a plain Python API (no Zenoh).

`submit()` and `set_posture()` may be called from any thread: they only queue. Every other
method, and the SML callbacks it triggers, runs on the one thread that owns the agent
(REFERENCE.md: an SML call from another thread while the agent runs deadlocks). The agent is
stepped, not free-running: `pump()` runs decision cycles until every queued input has been
put on the input link (one event per cycle, in order, from the before-input-phase callback)
and the agent has settled, and returns what came out on the output link.

One SoarAgent per process at a time: in soar-sml 9.6.5 shutting one kernel down while another
runs breaks the other's Python callbacks (a segfault at its next run; checked).
"""

from __future__ import annotations

import heapq
import itertools
import os
import re
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import soar_sml as sml

from services.runtime import get_logger

if TYPE_CHECKING:
    from schemas.messages import VoiceCommand

AGENT_DIR = Path(__file__).with_name("agent")
KNOWLEDGE_FILE = AGENT_DIR / "knowledge.soar"

POSTURES = ("sitting", "standing", "walking", "moving", "unknown")
_OUTPUT_ORDER = {"motion": 0, "remember": 1, "say": 2, "decision": 3, "explanation": 3, "ready": 4,
                 "timer": 5}
"""Within one output phase: motion first (safety latency), then persistence, then the rest."""

_AGENT_NUMBERS = itertools.count(1)
"""Agent names must be unique in a process: two kernels with same-named agents crash on
Shutdown (soar-sml 9.6.5, checked)."""
_NIL = "nil"
"""How the agent spells an absent optional field."""
_MAX_STAMPS = 4096
_WM_SIZE = re.compile(r"WM size:\s*(\d+) current")
_PRODUCTION = re.compile(r"sp\s*\{\s*([^\s\"(]+)")


class AgentLoadError(RuntimeError):
    """The kernel or the agent's rules could not be loaded; the message names file and rule."""


def _children(identifier: Any) -> dict[str, list[Any]]:
    """An output-link identifier's augmentations by attribute (identifiers converted)."""
    out: dict[str, list[Any]] = {}
    for i in range(identifier.GetNumberChildren()):
        wme = identifier.GetChild(i)
        value = wme.ConvertToIdentifier() if wme.IsIdentifier() else wme
        out.setdefault(wme.GetAttribute(), []).append(value)
    return out


def _values(identifier: Any) -> dict[str, str]:
    """Constant augmentations of an identifier; the agent's nil is left out."""
    values: dict[str, str] = {}
    for attr, wmes in _children(identifier).items():
        for wme in wmes:
            value = wme.GetValueAsString()
            if not wme.IsIdentifier() and value != _NIL:
                values[attr] = value
    return values


def _needed(values: dict[str, str], attr: str) -> str:
    if attr not in values:
        raise ValueError(f"^explanation part without ^{attr}")
    return values[attr]


def _float(value: str | None) -> float | None:
    return float(value) if value is not None else None


def _int(value: str | None) -> int | None:
    return int(value) if value is not None else None


# ---------------------------------------------------------------------------------- inputs
@dataclass(frozen=True)
class CommandInput:
    """A recognised utterance: `word` is None for speech that matched no command."""

    word: str | None
    confidence: float
    stamp: float | None = None

    @classmethod
    def of(cls, msg: VoiceCommand) -> CommandInput:
        """A published `VoiceCommand`, as the reasoner service (and a bench standing in for it) takes it."""
        return cls(word=msg.command.value if msg.command else None, confidence=msg.confidence, stamp=msg.stamp)


@dataclass(frozen=True)
class MarksInput:
    """Confirmed marks of one observation (an empty set carries no news and is not needed)."""

    shapes: frozenset[str]
    stamp: float | None = None


@dataclass(frozen=True)
class TimerInput:
    """A timer the agent started (a ^timer output) has run out; `key` is the agent's own."""

    key: int
    stamp: float | None = None


Event = CommandInput | MarksInput | TimerInput


@dataclass(frozen=True)
class Memory:
    """What survives a restart: the latched situation and a refused "go" awaiting an O
    (`resume_asks`: it was heard unsurely, so the O makes the robot ask before it walks)."""

    situation: str = "safe"
    resume_go: bool = False
    resume_asks: bool = False

    @property
    def resume_value(self) -> str:
        """The agent's ^resume-go: yes (walk on an O), ask (ask on an O) or no."""
        return ("ask" if self.resume_asks else "yes") if self.resume_go else "no"

    def __post_init__(self) -> None:
        if self.situation not in ("safe", "danger"):
            raise ValueError(f"situation must be 'safe' or 'danger', not {self.situation!r}")


# ---------------------------------------------------------------------------------- outputs
@dataclass(frozen=True)
class MotionOutput:
    action: str
    cause_stamp: float | None
    sustain: bool = False  # a lasting motion: keep it alive until another motion goal


@dataclass(frozen=True)
class SayOutput:
    text: str
    cause_stamp: float | None


@dataclass(frozen=True)
class DecisionOutput:
    command: str | None
    verdict: str
    reason: str
    action: str | None
    situation: str
    say: str | None
    cause_stamp: float | None


@dataclass(frozen=True)
class RememberOutput:
    memory: Memory


@dataclass(frozen=True)
class ReadyOutput:
    memory: Memory


@dataclass(frozen=True)
class EvidenceOutput:
    """Something the agent heard (kind command) or saw (kind mark), recalled from an episode."""

    role: str  # decision: what the explained decision answered; cause: the earlier episode's
    kind: str
    what: str
    stamp: float | None
    episode: int | None
    meaning: str | None = None  # a mark's meaning (danger | safe)


@dataclass(frozen=True)
class ExplanationOutput:
    """The agent's answer to "why": which sentence (`template`), the decision it explains as
    recalled from episodic memory (None: nothing decided yet), and the evidence."""

    template: str
    situation: str
    cause: int | None
    cause_stamp: float | None
    decision: DecisionOutput | None
    episode: int | None
    evidence: tuple[EvidenceOutput, ...] = ()


@dataclass(frozen=True)
class TimerOutput:
    """The agent asks for a ^timer input event with this key after `after_s` seconds. Handled by
    the host itself (never passed to the output sink)."""

    key: int
    after_s: float


Output = (MotionOutput | SayOutput | DecisionOutput | RememberOutput | ReadyOutput | TimerOutput
          | ExplanationOutput)


@dataclass(frozen=True)
class AgentConfig:
    rules_dir: Path = AGENT_DIR
    knowledge_file: Path = KNOWLEDGE_FILE
    debugger_port: int | None = None
    """Open the kernel listener on this port for the Soar Java debugger; None suppresses it."""
    settle_cycles: int = 8
    """Decision cycles run per step; pumping goes on while inputs or outputs keep coming."""
    max_busy_steps: int = 200
    """A pump gives up (and logs) after this many steps that still produce output without input."""
    ready_cycles: int = 400
    episodes: Path | None = None
    """The episodic-memory store (an SQLite file kept across restarts); None keeps it in memory."""
    episodes_max_bytes: int = 64 * 1024 * 1024
    """Above this size the store file is rotated: it becomes `<name>.1` (the one older generation
    kept) and a new one is started, so the episodes on disk never exceed twice this."""


class SoarAgent:
    """One Soar kernel (in its own thread) with the HRI agent loaded and initialised."""

    def __init__(
        self,
        config: AgentConfig | None = None,
        memory: Memory | None = None,
        *,
        on_output: Callable[[Output], None] | None = None,
        log: Any = None,
    ) -> None:
        self.config = config or AgentConfig()
        self.log = log or get_logger("reasoner")
        self._on_output = on_output
        self._lock = threading.Lock()
        self._events: deque[tuple[int, Event, float]] = deque()  # (input id, event, submitted at)
        self._pending_posture: str | None = None
        self._next_id = 0
        self._stamps: OrderedDict[int, float | None] = OrderedDict()
        self._to_complete: list[tuple[Any, bool]] = []  # handled commands to mark (ok or error)
        self._collected: list[Output] = []
        self._applied = 0
        self._produced = 0
        self._ready: Memory | None = None
        self.callback_errors = 0
        self.events_applied = 0
        self.episode_rotations = 0
        self._event_wme: Any = None
        self._memory_wme: Any = None
        self._motion_wme: Any = None
        self._posture_wme: Any = None
        self._posture = "unknown"
        self._closed = False
        self._timers: list[tuple[float, int]] = []  # (due on self.clock, key), a heap
        self.clock: Callable[[], float] = time.monotonic
        """The timers' clock (tests replace it)."""
        self.last_cycle = time.monotonic()
        """When the last decision cycle's input phase ran (monotonic seconds)."""

        port = self.config.debugger_port
        # The kernel lives in the thread that builds this object (the reasoner's Soar thread) and
        # runs inside its calls: no SML message crosses threads, which makes a decision about 3x
        # cheaper than with CreateKernelInNewThread. A debugger's requests are served between runs
        # by `serve_remote()`.
        self._kernel = sml.Kernel.CreateKernelInCurrentThread(
            True, port if port is not None else sml.Kernel.kSuppressListener
        )
        if self._kernel is None or self._kernel.HadError():
            detail = self._kernel.GetLastErrorDescription() if self._kernel is not None else "no kernel"
            raise AgentLoadError(f"cannot create the Soar kernel: {detail}")
        try:
            self._kernel.SetAutoCommit(False)
            number = next(_AGENT_NUMBERS)
            self._agent = self._kernel.CreateAgent("hri" if number == 1 else f"hri-{number}")
            if self._agent is None:
                detail = self._kernel.GetLastErrorDescription()
                raise AgentLoadError(f"cannot create the Soar agent: {detail}")
            self._open_episodes()
            self._load()
            # One callback per decision cycle (a Python callback costs about as much as a decision):
            # output is read at the start of the next input phase (right after the output phase)
            # and after each run.
            self._callback = self._guard(self._input_phase)
            self._agent.RegisterForRunEvent(sml.smlEVENT_BEFORE_INPUT_PHASE, self._callback, None)
            self._start(memory or Memory())
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------------------ loading
    def _open_episodes(self) -> None:
        """Point episodic memory at its file before the first episode (00_settings.soar turns it
        on). Committed per episode (lazy-commit off), so a SIGKILL loses none."""
        path = self.config.episodes
        if path is None:
            return
        if '"' in str(path) or "\n" in str(path):
            raise AgentLoadError(f"an episodic-memory file name cannot hold a quote or newline: {path}")
        path.parent.mkdir(parents=True, exist_ok=True)
        for command in ("epmem --set database file", f'epmem --set path "{path}"', "epmem --set append on",
                        "epmem --set lazy-commit off"):
            ok, out = self.execute(command)
            if not ok:
                raise AgentLoadError(f"episodic memory: `{command}` failed: {' '.join(out.split())}")

    def _bound_episodes(self) -> None:
        """Rotate the episodic-memory file once it is over its bound (owner thread, between runs).
        The agent keeps its latest decision in working memory, and the next episode stores it in
        the new file: "why" still answers for it. Older episodes are in `<name>.1` only."""
        path = self.config.episodes
        if path is None:
            return
        try:
            size = path.stat().st_size
        except FileNotFoundError:
            return
        if size <= self.config.episodes_max_bytes:
            return
        self.execute("epmem --close")
        try:
            os.replace(path, path.with_name(path.name + ".1"))
        except OSError as exc:  # the agent goes on in the same file; tried again after the next pump
            self.log.error("episodic memory not rotated", path=str(path), size=size, error=str(exc))
        else:
            self.episode_rotations += 1
            self.log.info("episodic memory rotated", path=str(path), size=size)
        ok, out = self.execute("epmem --init")
        if not ok:
            self.log.error("episodic memory not reopened", path=str(path), detail=" ".join(out.split())[:300])
        self.execute("epmem --set force remember")  # the new file starts with the latest decision

    def _load(self) -> None:
        rules = sorted(p for p in self.config.rules_dir.glob("*.soar") if p.name != KNOWLEDGE_FILE.name)
        if not rules:
            raise AgentLoadError(f"no *.soar rule files in {self.config.rules_dir}")
        for path in [*rules, self.config.knowledge_file]:
            self._source(path)

    def _source(self, path: Path) -> None:
        if not path.is_file():
            raise AgentLoadError(f"Soar file not found: {path}")
        before = self._production_names()
        out = self._agent.ExecuteCommandLine(f'source "{path}"')
        if self._agent.GetLastCommandLineResult():
            return
        # `source` stops at the first bad production: name it, with the first rule not loaded.
        loaded = self._production_names() - before
        declared = _PRODUCTION.findall(path.read_text(encoding="utf-8", errors="replace"))
        missing = next((name for name in declared if name not in loaded), None)
        where = f" at production {missing}" if missing else ""
        raise AgentLoadError(f"{path.name}: failed to load{where}: {' '.join(out.split())[:600]}")

    def _production_names(self) -> set[str]:
        out = self._agent.ExecuteCommandLine("print --all --name")
        return {line.strip() for line in out.splitlines() if line.strip()}

    # ------------------------------------------------------------------------------ lifecycle
    def _start(self, memory: Memory) -> None:
        il = self._agent.GetInputLink()
        self._memory_wme = self._agent.CreateIdWME(il, "memory")
        self._agent.CreateStringWME(self._memory_wme, "situation", memory.situation)
        self._agent.CreateStringWME(self._memory_wme, "resume-go", memory.resume_value)
        self._motion_wme = self._agent.CreateIdWME(il, "motion")
        self._posture_wme = self._agent.CreateStringWME(self._motion_wme, "posture", self._posture)
        self._agent.Commit()
        self._ready = None
        ran = 0
        while self._ready is None and ran < self.config.ready_cycles:
            self._run(self.config.settle_cycles)
            ran += self.config.settle_cycles
        if self._ready is None:
            raise AgentLoadError(
                f"the agent did not report ready within {ran} decision cycles (is the knowledge file "
                f"{self.config.knowledge_file} complete?): {self.execute('print --stack')[1].strip()}"
            )
        self.pump()  # let the ready command be cleaned up

    def reset(self, memory: Memory | None = None) -> Memory:
        """Re-initialise the agent (init-soar) from `memory`, keeping rules and knowledge. Fast."""
        with self._lock:
            self._events.clear()
            self._pending_posture = None
        self._stamps.clear()
        self._timers.clear()
        self._to_complete.clear()
        for attr in ("_event_wme", "_memory_wme", "_motion_wme"):
            wme = getattr(self, attr)
            if wme is not None:
                self._agent.DestroyWME(wme)
                setattr(self, attr, None)
        self._agent.Commit()
        self._posture = "unknown"
        self._agent.InitSoar()
        self._start(memory or Memory())
        assert self._ready is not None
        return self._ready

    @property
    def ready(self) -> Memory | None:
        """The memory the agent started from, once it reported ready."""
        return self._ready

    def close(self) -> None:
        """Shut the kernel down (always: REFERENCE.md). Idempotent."""
        if self._closed:
            return
        self._closed = True
        kernel = self.__dict__.pop("_kernel", None)
        self.__dict__.pop("_agent", None)
        if kernel is not None:
            kernel.Shutdown()
            del kernel

    def __enter__(self) -> SoarAgent:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------------------ input
    def submit(self, event: Event, reserve: Callable[[int], None] | None = None) -> int:
        """Queue an input event (any thread). Returns its input id (the `cause` of outputs);
        `reserve(id)` runs before the event can reach the agent (to wait for its answer)."""
        with self._lock:
            self._next_id += 1
            if reserve is not None:
                reserve(self._next_id)
            self._events.append((self._next_id, event, time.time()))
            return self._next_id

    def fire_timers(self) -> int:
        """Queue a TimerInput for every timer of the agent that has run out (owner thread)."""
        now = self.clock()
        fired = 0
        while self._timers and self._timers[0][0] <= now:
            _, key = heapq.heappop(self._timers)
            self.submit(TimerInput(key=key))
            fired += 1
        return fired

    def next_timer_in(self) -> float | None:
        """Seconds until the next timer runs out (None: no timer)."""
        return max(0.0, self._timers[0][0] - self.clock()) if self._timers else None

    def set_posture(self, posture: str) -> None:
        """Latest posture reported by the motion service (any thread); unknown values -> unknown."""
        with self._lock:
            self._pending_posture = posture if posture in POSTURES else "unknown"

    def pending(self) -> int:
        """Input events queued and not yet on the input link (the backlog)."""
        with self._lock:
            return len(self._events) + (self._pending_posture is not None)

    def _input_phase(self, _event_id: int, _data: Any, agent: Any, _phase: int) -> None:
        self.last_cycle = time.monotonic()
        self._read_output()
        changed = False
        if self._event_wme is not None:  # an event lives for exactly one decision cycle
            agent.DestroyWME(self._event_wme)
            self._event_wme = None
            changed = True
        if self._to_complete:
            for command, ok in self._to_complete:
                if ok:
                    command.AddStatusComplete()
                else:
                    command.AddStatusError()
            self._to_complete.clear()
            changed = True
        with self._lock:
            posture, self._pending_posture = self._pending_posture, None
            item = self._events.popleft() if self._events else None
        if posture is not None and posture != self._posture:
            self._posture = posture
            agent.Update(self._posture_wme, posture)
            changed = True
        if item is not None:
            self._put_event(agent, *item)
            changed = True
        if changed:
            agent.Commit()

    def _put_event(self, agent: Any, input_id: int, event: Event, submitted: float) -> None:
        self._stamps[input_id] = event.stamp
        while len(self._stamps) > _MAX_STAMPS:
            self._stamps.popitem(last=False)
        il = agent.GetInputLink()
        if isinstance(event, CommandInput):
            wme = agent.CreateIdWME(il, "command")
            if event.word is not None:
                agent.CreateStringWME(wme, "word", event.word)
            agent.CreateFloatWME(wme, "confidence", float(event.confidence))
        elif isinstance(event, MarksInput):
            wme = agent.CreateIdWME(il, "marks")
            for shape in sorted(event.shapes):
                agent.CreateStringWME(wme, "shape", shape)
        else:
            wme = agent.CreateIdWME(il, "timer")
            agent.CreateIntWME(wme, "key", event.key)
        agent.CreateIntWME(wme, "id", input_id)
        # When it was heard or seen (UNIX seconds): what the agent's episodes remember.
        agent.CreateFloatWME(wme, "time", float(event.stamp if event.stamp is not None else submitted))
        self._event_wme = wme
        self._applied += 1
        self.events_applied += 1

    # ------------------------------------------------------------------------------ output
    def _read_output(self) -> None:
        agent = self._agent
        if not agent.GetNumberCommands():
            return
        commands = [agent.GetCommand(i) for i in range(agent.GetNumberCommands())]
        agent.ClearOutputLinkChanges()
        parsed: list[tuple[int, Output]] = []
        for command in commands:
            name = command.GetCommandName()
            if command.GetParameterValue("status") is not None:
                continue
            try:
                out = self._parse(name, command)
            except ValueError as exc:  # a rule wrote a malformed command: report it, mark it
                self._to_complete.append((command, False))
                self.log.error("malformed output command", command=name, error=str(exc))
                continue
            self._to_complete.append((command, True))
            parsed.append((_OUTPUT_ORDER[name], out))
        for _, out in sorted(parsed, key=lambda p: p[0]):
            self._produced += 1
            if isinstance(out, ReadyOutput):
                self._ready = out.memory
            if isinstance(out, TimerOutput):
                heapq.heappush(self._timers, (self.clock() + out.after_s, out.key))
                continue
            self._collected.append(out)
            if self._on_output is not None:
                try:
                    self._on_output(out)
                except Exception:
                    self.callback_errors += 1
                    self.log.exception("output sink failed", output=repr(out))

    def _parse(self, name: str, cmd: Any) -> Output:
        """One output-link command as a dataclass; ValueError names what is missing or unknown."""

        def get(attr: str) -> str | None:
            value = cmd.GetParameterValue(attr)
            return None if value in (None, _NIL) else str(value)

        def need(attr: str) -> str:
            value = get(attr)
            if value is None:
                raise ValueError(f"^{name} without ^{attr}")
            return value

        if name == "motion":
            return MotionOutput(action=need("action"), cause_stamp=self._stamp(get("cause")),
                                sustain=get("sustain") == "yes")
        if name == "say":
            return SayOutput(text=need("text"), cause_stamp=self._stamp(get("cause")))
        if name == "decision":
            return DecisionOutput(
                command=get("command"), verdict=need("verdict"), reason=need("reason"), action=get("action"),
                situation=need("situation"), say=get("say"), cause_stamp=self._stamp(get("cause")),
            )
        if name == "explanation":
            return self._parse_explanation(cmd, get, need)
        if name == "timer":
            return TimerOutput(key=int(need("key")), after_s=float(need("after")))
        if name in ("remember", "ready"):
            resume = get("resume-go")
            memory = Memory(situation=need("situation"), resume_go=resume in ("yes", "ask"),
                            resume_asks=resume == "ask")
            return RememberOutput(memory) if name == "remember" else ReadyOutput(memory)
        raise ValueError(f"unknown output command ^{name}")

    def _parse_explanation(self, cmd: Any, get: Callable[[str], str | None],
                           need: Callable[[str], str]) -> ExplanationOutput:
        children = _children(cmd)
        decision = None
        episode = None
        if "decision" in children:
            d = _values(children["decision"][0])
            episode = _int(d.get("episode"))
            decision = DecisionOutput(
                command=d.get("command"), verdict=_needed(d, "verdict"), reason=_needed(d, "reason"),
                action=d.get("action"), situation=_needed(d, "situation"), say=None,
                cause_stamp=_float(d.get("time")),
            )
        evidence = []
        for wme in children.get("evidence", []):
            e = _values(wme)
            evidence.append(EvidenceOutput(
                role=_needed(e, "role"), kind=_needed(e, "kind"), what=_needed(e, "what"),
                stamp=_float(e.get("time")), episode=_int(e.get("episode")), meaning=e.get("shape-means"),
            ))
        cause = get("cause")
        return ExplanationOutput(
            template=need("template"), situation=need("situation"),
            cause=int(cause) if cause is not None and cause.lstrip("-").isdigit() else None,
            cause_stamp=self._stamp(cause), decision=decision, episode=episode,
            # the decision's own evidence first, then the earlier episode's; newest first within each
            evidence=tuple(sorted(evidence, key=lambda e: (e.role != "decision", -(e.stamp or 0.0), e.what))),
        )

    def _stamp(self, cause: str | None) -> float | None:
        if cause is None or not cause.lstrip("-").isdigit():
            return None
        return self._stamps.get(int(cause))

    # ------------------------------------------------------------------------------ running
    def pump(self) -> list[Output]:
        """Run until every queued input is handled and the agent has settled; return the outputs."""
        self._collected = []
        self.fire_timers()
        busy_steps = 0
        while True:
            applied, produced = self._applied, self._produced
            self._run(self.config.settle_cycles)
            if self.pending():
                busy_steps = 0
                continue
            if self._applied != applied:
                continue
            if self._produced != produced or self._to_complete:
                busy_steps += 1
                if busy_steps < self.config.max_busy_steps:
                    continue
                self.log.warning("agent keeps producing output without input", steps=busy_steps)
            break
        self._bound_episodes()
        out, self._collected = self._collected, []
        return out

    def _run(self, cycles: int) -> None:
        self._agent.RunSelf(cycles)
        try:
            self._read_output()  # what the last cycle of the run put on the output link
        except Exception:
            self.callback_errors += 1
            self.log.exception("reading the output link failed")

    def serve_remote(self) -> None:
        """Answer what a remote client (the Soar Java debugger) has sent since the last call; the
        kernel runs in this thread, so nothing else does. A no-op without a listener."""
        if self.config.debugger_port is not None:
            self._kernel.CheckForIncomingCommands()

    def step(self, *events: Event, posture: str | None = None) -> list[Output]:
        """Convenience for tests and tools: set the posture, queue `events`, pump."""
        if posture is not None:
            self.set_posture(posture)
        for event in events:
            self.submit(event)
        return self.pump()

    def execute(self, command: str) -> tuple[bool, str]:
        """Run a Soar command line on the agent (owner thread, between pumps): (ok, output)."""
        out = self._agent.ExecuteCommandLine(command)
        return bool(self._agent.GetLastCommandLineResult()), out

    def wm_size(self) -> int:
        """Working-memory elements now (from `stats`)."""
        match = _WM_SIZE.search(self.execute("stats")[1])
        return int(match.group(1)) if match else -1

    # ------------------------------------------------------------------------------ guards
    def _guard(self, fn: Callable[..., None]) -> Callable[..., None]:
        """An exception escaping an SML callback ends the process (REFERENCE.md): log it instead."""

        def guarded(*args: Any) -> None:
            try:
                fn(*args)
            except Exception:
                self.callback_errors += 1
                self.log.exception("Soar callback failed", callback=fn.__name__)

        return guarded
