"""What every service process shares: one Zenoh session, typed pub/sub, liveliness, health
and a clean stop on SIGTERM or Ctrl-C.

A service is a function `body(ctx)` run by `run_service`. The body declares its publishers and
subscribers on `ctx`, starts what it needs, and returns when `ctx.stopping` is set (usually by
looping on `ctx.wait(period)`). `run_service` then runs the registered cleanups and closes the
session in `finally`: a session left open hangs the interpreter's exit (REFERENCE.md).
"""

from __future__ import annotations

import os
import signal
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Generic, TypeVar

import zenoh
from pydantic import BaseModel

from schemas.keys import Keys
from schemas.messages import Header, Health, HealthStatus
from services.runtime import logs
from services.runtime.codec import DecodeError, decode, encode, encoding_for
from services.runtime.config import BusSettings, ConfigError
from services.runtime.logs import get_logger
from services.runtime.signals import relay_stop_signals

M = TypeVar("M", bound=BaseModel)
H = TypeVar("H", bound=Header)

PARENT_ENV = "HRI_LAUNCHER_PID"
"""Set by the launcher: a child whose parent is gone stops by itself (no orphans)."""


@dataclass
class Counters:
    """Message counters reported in `Health`; safe to bump from any thread."""

    received: int = 0
    published: int = 0
    rejected: int = 0
    callback_errors: int = 0
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def bump(self, name: str, n: int = 1) -> None:
        with self._lock:
            setattr(self, name, getattr(self, name) + n)


class TokenBucket:
    """At most `rate` events a second on average, in bursts of up to `burst` (one thread only)."""

    def __init__(self, rate: float, burst: int) -> None:
        self.rate = rate
        self.burst = float(burst)
        self.tokens = float(burst)
        self.last = time.monotonic()

    def take(self) -> bool:
        now = time.monotonic()
        self.tokens = min(self.burst, self.tokens + (now - self.last) * self.rate)
        self.last = now
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


class TypedPublisher(Generic[H]):
    """Publishes one model on one key, numbering messages with a per-publisher `seq`."""

    def __init__(self, ctx: ServiceContext, key: str, model: type[H], pub: zenoh.Publisher) -> None:
        self.key = key
        self.model = model
        self._ctx = ctx
        self._pub = pub
        self._seq = 0
        self._lock = threading.Lock()

    def put(self, msg: H) -> H:
        if not isinstance(msg, self.model):
            raise TypeError(f"{self.key} carries {self.model.__name__}, not {type(msg).__name__}")
        with self._lock:
            self._seq += 1
            msg.seq = self._seq
            self._pub.put(encode(msg))
        self._ctx.counters.bump("published")
        return msg

    @property
    def matched(self) -> bool:
        """Whether the bus knows of a subscriber for this key right now (Zenoh matching status)."""
        return bool(self._pub.matching_status.matching)


class ServiceContext:
    """One service's view of the bus. Built by `run_service`; also usable directly in tests."""

    def __init__(self, name: str, session: zenoh.Session, keys: Keys) -> None:
        self.name = name
        self.session = session
        self.keys = keys
        self.robot = keys.robot
        self.log = get_logger(name, robot=keys.robot)
        self.counters = Counters()
        self.stopping = threading.Event()
        self.started = time.monotonic()
        self._status = HealthStatus.OK
        self._detail: dict[str, Any] = {}
        self._detail_lock = threading.Lock()
        self._drops: dict[str, int] = {}
        self._cleanups: list[Callable[[], None]] = []
        self._keep: list[Any] = []  # declared zenoh entities: alive while referenced
        self._token = session.liveliness().declare_token(keys.alive(name))
        self._keep.append(
            session.declare_queryable(keys.health(name), self._guard(self._answer_health, "health"))
        )

    # ------------------------------------------------------------------ publish / subscribe
    def publisher(
        self,
        key: str,
        model: type[H],
        *,
        priority: zenoh.Priority | None = None,
        block: bool = False,
        express: bool = False,
    ) -> TypedPublisher[H]:
        """A typed publisher. `block=True` makes congestion block rather than drop (motion goals)."""
        pub = self.session.declare_publisher(
            key,
            encoding=encoding_for(model),
            congestion_control=zenoh.CongestionControl.BLOCK if block else zenoh.CongestionControl.DROP,
            priority=priority,
            express=express,
            reliability=zenoh.Reliability.RELIABLE,
        )
        self._keep.append(pub)
        return TypedPublisher(self, key, model, pub)

    def subscribe(
        self,
        key: str,
        model: type[M],
        callback: Callable[[M], None],
        *,
        latest_only: bool = False,
        queue: int | None = None,
        when: Callable[[], bool] | None = None,
        rate: float | None = None,
    ) -> None:
        """Deliver each valid `model` on `key` to `callback`; log, count and drop anything else.

        Callbacks run on Zenoh's threads one at a time and must be short. With
        `latest_only=True` a worker thread calls `callback` with the newest message only
        (a `RingChannel(1)`), for consumers that may fall behind (camera-rate marks).
        With `queue=n` Zenoh's thread only queues the sample (at most `n`; when full the oldest
        is dropped and counted in `Health.detail["dropped"]`) and a worker thread validates and
        delivers: a publisher flooding this key cannot hold up the session's other keys, nor
        grow this process's memory. `when` (with `queue`) holds delivery while it is false, so
        that nothing is validated that the consumer would only throw away (the queue keeps the
        newest meanwhile). `rate` (with `queue`) delivers at most that many messages a second
        (bursts up to `queue`); the rest are dropped unread and counted.
        """
        handle = self._guard(callback, f"subscriber {key}")

        def on_sample(sample: zenoh.Sample) -> None:
            msg = self._decode(sample, model)
            if msg is not None:
                handle(msg)

        if queue is not None:
            self._subscribe_bounded(key, on_sample, queue, when, rate)
            return
        if not latest_only:
            self._keep.append(self.session.declare_subscriber(key, self._guard(on_sample, key)))
            return
        sub = self.session.declare_subscriber(key, zenoh.handlers.RingChannel(1))
        self._keep.append(sub)

        def drain() -> None:
            while not self.stopping.is_set():
                try:
                    sample = sub.handler.recv()
                except Exception:  # channel closed with the session
                    return
                on_sample(sample)

        self.thread(drain, f"latest:{key}")

    def polled(self, key: str, model: type[M], size: int = 32) -> Callable[[], list[M]]:
        """The newest `size` valid `model`s on `key`, for a thread of the caller's to take when it wants them: the
        returned function empties the queue (never blocking; anything invalid logged, counted and dropped, as by
        `subscribe`). Zenoh fills a `RingChannel` (the oldest dropped when full) and no thread or Python callback of
        Zenoh's waits on it, so none can wake while the process exits (a callback's own thread can)."""
        if size < 1:
            raise ValueError(f"queue size for {key} must be at least 1, not {size}")
        sub = self.session.declare_subscriber(key, zenoh.handlers.RingChannel(size))
        self._keep.append(sub)

        def take() -> list[M]:
            out: list[M] = []
            while True:
                try:
                    sample = sub.handler.try_recv()
                except Exception:  # channel closed with the session
                    return out
                if sample is None:
                    return out
                msg = self._decode(sample, model)
                if msg is not None:
                    out.append(msg)

        return take

    def _subscribe_bounded(self, key: str, deliver: Callable[[zenoh.Sample], None], size: int,
                           when: Callable[[], bool] | None, rate: float | None) -> None:
        if size < 1:
            raise ValueError(f"queue size for {key} must be at least 1, not {size}")
        bucket = TokenBucket(rate, size) if rate else None
        pending: deque[zenoh.Sample] = deque(maxlen=size)
        wake = threading.Event()

        def on_sample(sample: zenoh.Sample) -> None:  # Zenoh's thread: queue and return
            if len(pending) == size:
                self.count_drop(key)
            pending.append(sample)
            wake.set()

        guarded = self._guard(deliver, key)

        def drain() -> None:
            while not self.stopping.is_set():
                if when is not None and pending and not when():
                    self.stopping.wait(0.001)  # the consumer is busy: let the queue shed the oldest
                    continue
                try:
                    sample = pending.popleft()
                except IndexError:
                    wake.wait(0.2)
                    wake.clear()
                    continue
                if bucket is not None and not bucket.take():
                    self.count_drop(key)
                    continue
                guarded(sample)

        self._keep.append(self.session.declare_subscriber(key, on_sample))
        self.thread(drain, f"queue:{key}")

    def count_drop(self, key: str, n: int = 1) -> None:
        """Count messages dropped on `key` because the service could not keep up (a flood)."""
        short = key[len(self.keys.prefix) + 1:] if key.startswith(self.keys.prefix + "/") else key
        with self._detail_lock:
            self._drops[short] = self._drops.get(short, 0) + n

    @property
    def drops(self) -> dict[str, int]:
        with self._detail_lock:
            return dict(self._drops)

    def _decode(self, sample: zenoh.Sample, model: type[M]) -> M | None:
        self.counters.bump("received")
        payload = sample.payload.to_bytes()
        try:
            return decode(payload, model)
        except DecodeError as exc:
            self.counters.bump("rejected")
            self.log.warning(
                "rejected payload",
                key=str(sample.key_expr),
                error=str(exc),
                payload=payload[:120].decode("utf-8", "replace"),
            )
            return None

    def on_liveliness(self, key: str, callback: Callable[[str, bool], None], *, history: bool = True) -> None:
        """`callback(key, alive)` when a liveliness token matching `key` appears or goes."""
        handle = self._guard(callback, f"liveliness {key}")

        def on_sample(sample: zenoh.Sample) -> None:
            handle(str(sample.key_expr), sample.kind == zenoh.SampleKind.PUT)

        self._keep.append(
            self.session.liveliness().declare_subscriber(key, self._guard(on_sample, key), history=history)
        )

    def queryable(self, key: str, answer: Callable[[str, bytes], BaseModel | str]) -> None:
        """Answer `session.get(key)` with `answer(parameters, payload)`; an exception replies an error."""

        def on_query(query: zenoh.Query) -> None:
            payload = query.payload.to_bytes() if query.payload is not None else b""
            try:
                result = answer(str(query.parameters), payload)
            except Exception as exc:  # reported to the asker, not fatal here
                self.counters.bump("callback_errors")
                self.log.warning("query failed", key=key, error=str(exc))
                query.reply_err(str(exc))
                return
            if isinstance(result, BaseModel):
                query.reply(key, encode(result), encoding=encoding_for(type(result)))
            else:
                query.reply(key, str(result), encoding=zenoh.Encoding.TEXT_PLAIN)

        self._keep.append(self.session.declare_queryable(key, self._guard(on_query, key)))

    # ------------------------------------------------------------------ health
    def set_status(self, status: HealthStatus, **detail: Any) -> None:
        """Set health status; `detail` entries are merged into `Health.detail`."""
        with self._detail_lock:
            if status != self._status:
                self.log.info("health", status=status.value, **detail)
            self._status = status
            self._detail.update(detail)

    def update_detail(self, **detail: Any) -> None:
        with self._detail_lock:
            self._detail.update(detail)

    @property
    def status(self) -> HealthStatus:
        return self._status

    def health(self) -> Health:
        with self._detail_lock:
            detail = dict(self._detail)
            if self._drops:
                detail["dropped"] = dict(self._drops)
        detail["callback_errors"] = self.counters.callback_errors
        detail.setdefault("pid", os.getpid())
        return Health(
            service=self.name,
            status=self._status,
            uptime_s=round(time.monotonic() - self.started, 3),
            received=self.counters.received,
            published=self.counters.published,
            rejected=self.counters.rejected,
            detail=detail,
        )

    def _answer_health(self, query: zenoh.Query) -> None:
        query.reply(self.keys.health(self.name), encode(self.health()), encoding=encoding_for(Health))

    def query_health(self, service: str, timeout: float = 2.0) -> Health | None:
        """Ask another service on the bus for its `Health`: None when nobody answers within
        `timeout` seconds or the answer is not a valid `Health` (logged)."""
        for reply in self.session.get(self.keys.health(service), timeout=timeout):
            if reply.ok is None:
                continue
            try:
                return decode(reply.ok.payload.to_bytes(), Health)
            except DecodeError as exc:
                self.log.warning("invalid health reply", service=service, error=str(exc))
                return None
        return None

    # ------------------------------------------------------------------ lifecycle
    def wait(self, timeout: float | None = None) -> bool:
        """Sleep up to `timeout` seconds; True once the service is asked to stop."""
        return self.stopping.wait(timeout)

    def stop(self) -> None:
        self.stopping.set()

    def on_close(self, fn: Callable[[], None]) -> None:
        """Run `fn` at shutdown, before the session closes (last registered runs first)."""
        self._cleanups.append(fn)

    def thread(self, target: Callable[[], None], name: str) -> threading.Thread:
        """Start a daemon thread whose exceptions are logged and counted, never fatal."""
        t = threading.Thread(target=self._guard(target, name), name=f"{self.name}:{name}", daemon=True)
        t.start()
        return t

    def _guard(self, fn: Callable[..., Any], where: str) -> Callable[..., Any]:
        def guarded(*args: Any) -> Any:
            try:
                return fn(*args)
            except Exception:
                self.counters.bump("callback_errors")
                self.log.exception("callback failed", where=where)
                return None

        return guarded

    def close(self) -> None:
        """Run cleanups, drop the token and declarations, close the session. Idempotent."""
        self.stopping.set()
        while self._cleanups:
            fn = self._cleanups.pop()
            try:
                fn()
            except Exception:
                self.log.exception("cleanup failed", cleanup=getattr(fn, "__qualname__", repr(fn)))
        for obj in reversed(self._keep):
            try:
                obj.undeclare()
            except Exception:  # already undeclared or session gone
                pass
        self._keep.clear()
        try:
            self._token.undeclare()
        except Exception:
            pass
        if not self.session.is_closed():
            self.session.close()


def open_session(settings: BusSettings, log: Any, *, attempts: int = 0,
                 stop: threading.Event | None = None) -> zenoh.Session:
    """Open a session. zenoh clients fail at once when no router answers, or when the router
    refuses their credentials; retry, logging why each time (a robot waits for its router to come up).

    `attempts=0` retries until `stop` is set, which raises `SessionStopped` within about half a second.
    """
    stop = stop or threading.Event()
    delay, n = 0.2, 0
    while True:
        n += 1
        settings = settings.refreshed()
        try:
            return _open(settings.zenoh_config(), stop)
        except (ConfigError, SessionStopped):
            raise
        except Exception as exc:
            why, refused = why_not_open(settings)
            open_bus = _open_anonymously(settings, log, stop) if refused else None
            if open_bus is not None:
                return open_bus
            if attempts and n >= attempts:  # a person waits: say why in one line
                raise SessionRefused(why, refused=refused) from exc
            if not attempts:
                event = ("the router refused this session, retrying" if refused
                         else "no zenoh router yet, retrying")
                log.warning(event, why=why, retry_in_s=delay)
            if stop.wait(delay):
                raise SessionStopped from None
            delay = min(delay * 2, 3.0)


def _open(config: zenoh.Config, stop: threading.Event) -> zenoh.Session:
    """`zenoh.open` in a helper thread. It blocks in native code for as long as a router that
    accepts the connection takes to answer (seconds, for a stuck handshake); meanwhile this thread
    watches `stop`, so a SIGTERM or Ctrl-C still stops the process at once. A session that opens
    after that is closed by the helper: nobody will use it."""
    result: list[zenoh.Session | BaseException] = []
    handover = threading.Lock()
    gave_up: list[bool] = []

    def target() -> None:
        try:
            outcome: zenoh.Session | BaseException = zenoh.open(config)
        except BaseException as exc:  # handed to the caller's thread
            outcome = exc
        with handover:
            if gave_up and isinstance(outcome, zenoh.Session):
                outcome.close()
            result.append(outcome)

    opener = threading.Thread(target=target, name="zenoh-open", daemon=True)
    opener.start()
    while opener.is_alive():
        if stop.is_set():
            with handover:
                gave_up.append(True)
                if result and isinstance(result[0], zenoh.Session):
                    result[0].close()
            raise SessionStopped
        opener.join(0.05)
    if isinstance(result[0], BaseException):
        raise result[0]
    return result[0]


def _open_anonymously(settings: BusSettings, log: Any, stop: threading.Event) -> zenoh.Session | None:
    """A router without authentication refuses clients that offer credentials. Such a router is
    open to anyone anyway, so join it without them (saying so) rather than not at all."""
    if settings.credentials is None or settings.config_file is not None:
        return None
    try:
        session = _open(replace(settings, credentials=None, identity=None).zenoh_config(), stop)
    except SessionStopped:
        raise
    except Exception:
        return None
    log.warning("the router asks no credentials: joined an OPEN bus", endpoints=",".join(settings.connect),
                identity=settings.who)
    return session


class SessionStopped(Exception):
    """The process was asked to stop while its session was still opening."""


class SessionRefused(RuntimeError):
    """No session could be opened; the message is one line saying why and what to do.
    `refused`: a router is there and refused (else nobody answered)."""

    def __init__(self, why: str, *, refused: bool) -> None:
        super().__init__(why)
        self.refused = refused


def why_not_open(settings: BusSettings) -> tuple[str, bool]:
    """One line: nobody listens at the endpoints, or a router is there and refused us (True)."""
    where = ",".join(settings.connect)
    listening = [e for e in settings.connect if _accepts(e)]
    if not listening:
        return f"no zenoh router at {where}; start one (`hri up`) or point HRI_ZENOH_CONNECT at it", False
    if settings.credentials is None:
        return (f"the router at {listening[0]} refused an anonymous session; it requires credentials: "
                "set HRI_CREDENTIALS=<keys dir>/<identity> (see `hri keys init`)"), True
    return (f"the router at {listening[0]} refused identity {settings.credentials.user!r} "
            f"({settings.credentials.folder}): wrong password or certificate for this deployment?"), True


def _accepts(endpoint: str) -> bool:
    proto, _, address = endpoint.partition("/")
    if proto not in ("tcp", "tls") or ":" not in address:
        return False
    host, _, port = address.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port.split("#")[0])), timeout=0.5):
            return True
    except (OSError, ValueError):
        return False


def run_service(
    name: str,
    body: Callable[[ServiceContext], None],
    *,
    robot: str | None = None,
    connect: str | None = None,
    identity: str | None = None,
) -> int:
    """Run one service process: open the session, serve `body(ctx)`, close cleanly. Returns an exit code.

    The session's credentials are those of `identity` (default: the service's own name); the tools
    (`hri record`, `replay`, `view`) run as the observer or the operator.
    """
    log = get_logger(name)
    if problem := logs.settings_error():
        log.error("configuration error", error=problem)
        return 2
    try:
        settings = BusSettings.from_env(robot=robot, connect=connect, identity=identity or name)
    except ConfigError as exc:
        log.error("configuration error", error=str(exc))
        return 2
    stop_requested = threading.Event()
    ctx_box: list[ServiceContext] = []

    def on_signal(sig: signal.Signals) -> None:  # in the relay's thread, never inside the handler
        if stop_requested.is_set():  # second Ctrl-C: the user means it
            threading.Timer(0.5, os._exit, (128 + sig,)).start()  # even if the log cannot take the line
            log.warning("second signal, exiting now", signal=sig.name)
            os._exit(128 + sig)
        stop_requested.set()
        log.info("stopping", signal=sig.name)
        for ctx in ctx_box:
            ctx.stop()

    relay_stop_signals(on_signal)
    try:
        session = open_session(settings, log, stop=stop_requested)
    except SessionStopped:
        log.info("stopped before the session opened")
        return 0
    except ConfigError as exc:
        log.error("configuration error", error=str(exc))
        return 2
    ctx: ServiceContext | None = None
    try:
        ctx = ServiceContext(name, session, Keys(settings.robot))
        ctx_box.append(ctx)
        if stop_requested.is_set():
            ctx.stop()
        _watch_parent(ctx)
        ctx.log.info("started", pid=os.getpid(), endpoints=",".join(settings.connect), identity=settings.who,
                     config_file=str(settings.config_file) if settings.config_file else None)
        body(ctx)
        return 0
    except Exception:
        log.exception("service failed")
        return 1
    finally:
        if ctx is not None:
            ctx.close()
        elif not session.is_closed():
            session.close()
        log.info("stopped")


def _watch_parent(ctx: ServiceContext) -> None:
    """Under the launcher, stop when the launcher is gone, even if it was SIGKILLed."""
    raw = os.environ.get(PARENT_ENV)
    if not raw or not raw.isdigit():
        return
    parent = int(raw)

    def watch() -> None:
        while not ctx.wait(0.5):
            if os.getppid() != parent:
                ctx.stop()
                ctx.log.warning("launcher gone, stopping", launcher_pid=parent)
                return

    ctx.thread(watch, "parent-watch")
