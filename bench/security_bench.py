"""What authentication and access control cost, and whether a flood keeps the robot from stopping.

    python bench/security_bench.py [--messages 3000] [--commands 16] [--rounds 3]
                                    [--flood-rate 50000] [--flood-s 5] [--stops 3] [--only bus|servo|flood]

- bus: one-way latency of a `VoiceCommand` from a publisher process to a subscriber process through
  the router (zenoh-python), open / user-password + access rules on loopback TCP / mutual TLS + user-
  password + access rules (publisher `voice`, subscriber `reasoner`, as in a deployment);
- command -> servo: `VoiceCommand` published to the first servo write carrying its motion, over the
  five real processes on the simulated OP2 (bench/system_latency.py's measurement), open and secured;
- flood: the secured robot walks; another process, authenticated as an identity allowed to put
  (`voice` for `VoiceCommand`, `vision` for `MarkObservation`), floods at `--flood-rate`; after 2 s of
  flood an X is held up (synthetic camera) and the time to the reasoner's `stop` goal and to its
  first servo write is taken; the reasoner's resident memory and the drops its health reports.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import tempfile
import threading
import time
from pathlib import Path

import bus_latency  # noqa: I001 - bench siblings, run as `python bench/security_bench.py`
import system_latency
import zenoh

from schemas import (
    Action,
    MarkObservation,
    MotionGoal,
    MotionState,
    Posture,
    SceneCommand,
    Shape,
    VoiceCommand,
)
from schemas.keys import Keys
from services.cli import keys as deployment_keys
from services.cli.launcher import Launcher
from services.cli.router import Router, free_port, loopback_endpoint, wait_listening
from services.cli.simrobot import simulated_env, simulated_robot
from services.runtime import (
    Credentials,
    RouterSecurity,
    ServiceContext,
    client_config,
    configure_logging,
    encode,
)


# ---------------------------------------------------------------------------------------- bus
def bus(keys: Path, messages: int, rate: float, rounds: int) -> None:
    """The three modes in turn, `rounds` times (a shared machine's load drifts: interleave)."""
    robot = "benchsec"
    creds = (keys / "reasoner", keys / "voice")
    modes = {
        "open (no auth, no rules)    ": (None, "tcp", (None, None)),
        "user/password + access rules": (RouterSecurity(keys, robot=robot), "tcp", creds),
        "mutual TLS + user/pw + rules": (RouterSecurity(keys, robot=robot), "tls", creds),
    }
    samples: dict[str, list[float]] = {label: [] for label in modes}
    for _ in range(rounds):
        for label, (security, link, who) in modes.items():
            port, tls_port = free_port(), free_port()
            tcp = loopback_endpoint(port)
            listen = [tcp] if security is None else [tcp, f"tls/127.0.0.1:{tls_port}"]
            with Router(listen, security):
                wait_listening(port)
                endpoint = tcp if link == "tcp" else f"tls/localhost:{tls_port}"
                lat, _ = bus_latency.run(messages, rate, endpoint, robot, who)
            samples[label] += [x * 1000 for x in lat]
    for label, ms in samples.items():
        print(
            f"bus, {label}: {len(ms)} msgs at {rate:.0f}/s in {rounds} rounds: "
            f"p50 {bus_latency.pct(ms, 50):.3f} ms   p99 {bus_latency.pct(ms, 99):.3f} ms"
        )


# ---------------------------------------------------------------------------------------- command -> servo
def servo(commands: int, rounds: int) -> None:
    args = argparse.Namespace(commands=commands, stops=0, utterances=0)
    samples: dict[bool, list[float]] = {False: [], True: []}
    for _ in range(rounds):
        for secure in (False, True):
            out = Path(tempfile.mkdtemp(prefix="hri-secbench-"))
            with simulated_robot(
                out, robot="benchservo", participant="bench", env={"HRI_LOG_LEVEL": "warning"}, secure=secure
            ) as sim:
                samples[secure] += system_latency.measure(sim, args).cmd
    for secure, xs in samples.items():
        label = "secured" if secure else "open   "
        print(f"command -> first servo write, {label}: {system_latency.pcts(xs)}")


# ---------------------------------------------------------------------------------------- flood
def _flood(
    endpoint: str, creds: str, key: str, payload: bytes, rate: float, seconds: float, out: mp.Queue
) -> None:
    """Put `payload` on `key` at `rate` per second (batches every millisecond) for `seconds`."""
    session = zenoh.open(client_config([endpoint], Credentials.load(Path(creds))))
    try:
        pub = session.declare_publisher(key, congestion_control=zenoh.CongestionControl.DROP)
        per_ms = max(1, int(rate / 1000))
        sent, t0 = 0, time.perf_counter()
        while (now := time.perf_counter()) - t0 < seconds:
            due = int((now - t0) * rate)
            burst = min(per_ms, due - sent) if due > sent else 0
            for _ in range(burst):
                pub.put(payload)
            sent += burst
            if burst == 0:
                time.sleep(0.0005)
        out.put((sent, time.perf_counter() - t0))
    finally:
        session.close()


class Watch:
    """The bench's own participant (operator): motion goals and states only, so the flood does not
    land in this process too."""

    def __init__(self, ctx: ServiceContext) -> None:
        self.ctx = ctx
        self.goals: list[tuple[float, MotionGoal]] = []
        self.state: MotionState | None = None
        self.writes: dict[str, float] = {}
        self.cond = threading.Condition()
        self.x_seen: list[
            tuple[float, float]
        ] = []  # (vision's stamp, arrival here) of observations with an X
        self._raw = ctx.session.declare_subscriber(ctx.keys.vision_marks, self._marks)  # cheap: no decode
        ctx.subscribe(ctx.keys.motion_goal, MotionGoal, self._goal)
        ctx.subscribe(ctx.keys.motion_state, MotionState, self._state)
        self.scene = ctx.publisher(ctx.keys.vision_scene, SceneCommand)
        self.voice = ctx.publisher(ctx.keys.voice_command, VoiceCommand)

    def _marks(self, sample: zenoh.Sample) -> None:
        raw = sample.payload.to_bytes()
        if b'"X"' in raw:
            obs = MarkObservation.model_validate_json(raw)
            with self.cond:
                self.x_seen.append((obs.stamp, time.time()))

    def _goal(self, g: MotionGoal) -> None:
        with self.cond:
            self.goals.append((time.time(), g))
            self.cond.notify_all()

    def _state(self, s: MotionState) -> None:
        with self.cond:
            self.state = s
            if s.goal_id and s.first_write:
                self.writes.setdefault(s.goal_id, s.first_write)
            self.cond.notify_all()

    def wait(self, predicate, timeout: float):  # type: ignore[no-untyped-def]
        with self.cond:
            return self.cond.wait_for(predicate, timeout)

    def posture(self, p: Posture, timeout: float = 15) -> bool:
        return bool(
            self.wait(
                lambda: (
                    self.state is not None
                    and self.state.posture == p
                    and (self.state.action is None or p == Posture.WALKING)
                ),
                timeout,
            )
        )

    def say(self, word: str) -> None:
        self.voice.put(
            VoiceCommand(command=word, text=word, confidence=0.99, engine="bench", stamp=time.time())
        )


def flood(keys: Path, rate: float, stops: int, flood_s: float, kinds: list[str]) -> None:
    robot = "benchflood"
    out = Path(tempfile.mkdtemp(prefix="hri-flood-"))
    (out / "spool").mkdir()
    log = (out / "services.log").open("w")
    lock = threading.Lock()

    def sink(name: str, line: str) -> None:
        with lock:
            log.write(f"{name:<8} | {line}\n")

    port = free_port()
    launcher = Launcher(
        port=port,
        robot=robot,
        env={**simulated_env(out), "HRI_LOG_LEVEL": "warning"},
        sink=sink,
        keys_dir=keys,
    )
    k = Keys(robot)
    payloads = {
        "VoiceCommand": (
            k.voice_command,
            "voice",
            encode(VoiceCommand(command="go", text="go", confidence=0.99, engine="flood", stamp=1.0)),
        ),
        "MarkObservation": (k.vision_marks, "vision", encode(MarkObservation(marks=[], frame=1, stamp=1.0))),
    }
    spawn = mp.get_context("spawn")
    with launcher:
        ctx = ServiceContext(
            "bench", zenoh.open(client_config([launcher.endpoint], Credentials.load(keys / "operator"))), k
        )
        try:
            watch = Watch(ctx)
            ready = watch.wait(
                lambda: watch.state is not None and watch.state.bus_ok and watch.scene.matched, 90
            )
            while not ((h := ctx.query_health("reasoner", 1.0)) and h.detail.get("ready")):
                time.sleep(0.3)
            if not ready:
                raise SystemExit(f"robot did not come up; see {out / 'services.log'}")
            for variant in (None, *[p for p in payloads if p in kinds]):
                to_goal, to_write, to_seen, sent_rates, rss = [], [], [], [], []
                for _ in range(stops):
                    watch.scene.put(SceneCommand(shape=Shape.O))
                    time.sleep(0.8)
                    watch.scene.put(SceneCommand(shape=None))
                    watch.say("go")
                    if not watch.posture(Posture.WALKING):
                        print(f"  ({variant or 'no flood'}: the robot did not walk; skipped)")
                        continue
                    proc, q = None, spawn.Queue()
                    if variant:
                        key, who, payload = payloads[variant]
                        proc = spawn.Process(
                            target=_flood,
                            args=(launcher.endpoint, str(keys / who), key, payload, rate, flood_s, q),
                        )
                        proc.start()
                        time.sleep(2.0)
                    shown = time.time()
                    watch.scene.put(SceneCommand(shape=Shape.X))
                    stop = watch.wait(
                        lambda: next(
                            (g for t, g in watch.goals if t >= shown and g.action == Action.STOP), None
                        ),
                        10,
                    )
                    seen = next((stamp for stamp, _ in watch.x_seen if stamp >= shown), None)
                    if seen:
                        to_seen.append(seen - shown)
                    if stop:
                        to_goal.append(next(t for t, g in watch.goals if g is stop) - shown)
                        if watch.wait(lambda: stop.goal_id in watch.writes, 5):
                            to_write.append(watch.writes[stop.goal_id] - shown)
                    pid = launcher.pid("reasoner")
                    if pid:
                        rss.append(system_latency.rss_mib(pid))
                    if proc is not None:
                        sent, span = q.get(timeout=flood_s + 30)
                        proc.join(10)
                        sent_rates.append(sent / span)
                    watch.scene.put(SceneCommand(shape=None))
                    time.sleep(1.0)
                health = ctx.query_health("reasoner", 2.0)
                drops = {n: v for n, v in (health.detail if health else {}).items() if "drop" in n}
                label = (
                    f"flood of {variant} at {sum(sent_rates) / max(1, len(sent_rates)):,.0f}/s"
                    if variant
                    else "no flood"
                )
                print(f"{label}:")
                print(f"   X shown -> vision reports it:      {system_latency.pcts(to_seen)}")
                print(f"   X shown -> stop goal:              {system_latency.pcts(to_goal)}")
                print(f"   X shown -> stop's first servo write: {system_latency.pcts(to_write)}")
                print(
                    f"   reasoner RSS {', '.join(f'{r:.0f}' for r in rss)} MiB; health {drops}; "
                    f"received {health.received if health else '?'}"
                )
        finally:
            ctx.close()
    log.close()
    print(f"(service logs in {out / 'services.log'})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--messages", type=int, default=3000)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--commands", type=int, default=16)
    ap.add_argument("--flood-rate", type=float, default=50000.0)
    ap.add_argument("--flood-s", type=float, default=5.0, help="seconds each flood lasts")
    ap.add_argument("--stops", type=int, default=3)
    ap.add_argument("--flood-kind", choices=["VoiceCommand", "MarkObservation"], action="append")
    ap.add_argument(
        "--rounds", type=int, default=3, help="bus and servo modes are measured in turn this often"
    )
    ap.add_argument("--only", choices=["bus", "servo", "flood"], action="append")
    args = ap.parse_args()
    configure_logging("warning")
    keys = Path(tempfile.mkdtemp(prefix="hri-keys-")) / "keys"
    deployment_keys.init(keys)
    parts = args.only or ["bus", "servo", "flood"]
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    if "bus" in parts:
        bus(keys, args.messages, args.rate, args.rounds)
    if "servo" in parts:
        servo(args.commands, args.rounds)
    if "flood" in parts:
        kinds = args.flood_kind or ["VoiceCommand", "MarkObservation"]
        flood(keys, args.flood_rate, args.stops, args.flood_s, kinds)


if __name__ == "__main__":
    main()
