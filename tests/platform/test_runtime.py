"""The shared Zenoh runtime over a real router: typed pub/sub, rejection, health, liveliness, config."""

from __future__ import annotations

import itertools
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import cast

import pytest
import zenoh

from schemas import Health, HealthStatus, Keys, MarkObservation, VoiceCommand
from services.cli.router import free_port
from services.runtime import BusSettings, ConfigError, ServiceContext, client_config
from tests.conftest import ROOT, alive_services, read_lines, service_env, wait_for


@pytest.fixture
def peer(router_endpoint: str, keys: Keys):
    ctx = ServiceContext("peer", zenoh.open(client_config([router_endpoint])), keys)
    yield ctx
    ctx.close()


def test_typed_messages_arrive_validated_and_numbered(bus: ServiceContext, peer: ServiceContext) -> None:
    got: list[VoiceCommand] = []
    encodings: list[str] = []
    bus.subscribe(bus.keys.voice_command, VoiceCommand, got.append)
    bus.session.declare_subscriber(bus.keys.voice_command, lambda s: encodings.append(str(s.encoding)))
    pub = peer.publisher(peer.keys.voice_command, VoiceCommand)
    wait_for(lambda: pub.matched)
    for word in ("stand", "go"):
        pub.put(VoiceCommand(command=word, text=word, confidence=0.9, engine="test"))
    # the raw subscriber's callbacks may run after the typed one's on a loaded machine (CI-exact, stop 89)
    wait_for(lambda: len(got) == 2 and len(encodings) == 2)
    assert [m.command.value for m in got] == ["stand", "go"]
    assert [m.seq for m in got] == [1, 2]
    assert encodings[0] == "application/json;VoiceCommand"
    assert peer.counters.published == 2 and bus.counters.received >= 2


def test_bad_payloads_are_counted_and_dropped(bus: ServiceContext, peer: ServiceContext) -> None:
    got: list[MarkObservation] = []
    bus.subscribe(bus.keys.vision_marks, MarkObservation, got.append)
    probe = peer.publisher(peer.keys.vision_marks, MarkObservation)
    wait_for(lambda: probe.matched)
    for garbage in (b"not json", b"{}", b'{"marks":[{"shape":"STAR","confidence":1,"box":[0,0,1,1]}]}',
                    b"\xff\xfe", b'{"marks": "X"}'):
        peer.session.put(peer.keys.vision_marks, garbage)
    peer.session.put(peer.keys.vision_marks, MarkObservation(frame=9).model_dump_json())
    wait_for(lambda: len(got) == 2)
    assert [m.frame for m in got] == [0, 9]  # "{}" is a valid observation: every field has a default
    assert bus.counters.rejected == 4


def test_a_failing_callback_is_counted_not_fatal(bus: ServiceContext, peer: ServiceContext) -> None:
    calls: list[int] = []

    def explode(msg: VoiceCommand) -> None:
        calls.append(msg.seq)
        raise RuntimeError("boom")

    bus.subscribe(bus.keys.voice_command, VoiceCommand, explode)
    pub = peer.publisher(peer.keys.voice_command, VoiceCommand)
    wait_for(lambda: pub.matched)
    pub.put(VoiceCommand(command="go", confidence=1))
    pub.put(VoiceCommand(command="go", confidence=1))
    wait_for(lambda: len(calls) == 2)
    assert bus.counters.callback_errors == 2


def test_latest_only_subscriber_skips_to_the_newest(bus: ServiceContext, peer: ServiceContext) -> None:
    seen: list[int] = []

    def slow(msg: MarkObservation) -> None:
        seen.append(msg.frame)
        time.sleep(0.2)

    bus.subscribe(bus.keys.vision_marks, MarkObservation, slow, latest_only=True)
    pub = peer.publisher(peer.keys.vision_marks, MarkObservation)
    wait_for(lambda: pub.matched)
    for frame in range(1, 51):
        pub.put(MarkObservation(frame=frame))
    wait_for(lambda: seen and seen[-1] == 50, timeout=5)
    assert len(seen) < 10, seen


def test_a_polled_subscription_hands_over_the_newest_valid_messages_without_blocking(
    bus: ServiceContext, peer: ServiceContext
) -> None:
    threads = {t.name for t in threading.enumerate()}
    take = bus.polled(bus.keys.voice_command, VoiceCommand, size=3)
    assert take() == []  # nothing yet, and no waiting for it
    assert {t.name for t in threading.enumerate()} == threads  # no thread of its own
    arrived: list[bytes] = []
    _count = bus.session.declare_subscriber(bus.keys.voice_command, lambda s: arrived.append(s.payload.to_bytes()))
    pub = peer.publisher(peer.keys.voice_command, VoiceCommand)
    wait_for(lambda: pub.matched)
    peer.session.put(peer.keys.voice_command, b"not json")
    for word in ("stand", "yes", "no", "go"):
        pub.put(VoiceCommand(command=word, confidence=1))
    wait_for(lambda: len(arrived) == 5)
    time.sleep(0.1)  # the same session's other subscriber: delivered together
    assert [m.command.value for m in take()] == ["yes", "no", "go"]  # the newest 3; the oldest dropped unread
    assert take() == []
    rejected = bus.counters.rejected
    peer.session.put(peer.keys.voice_command, b"not json")
    wait_for(lambda: len(arrived) == 6)
    time.sleep(0.1)
    assert take() == [] and bus.counters.rejected == rejected + 1  # invalid: logged, counted, dropped
    with pytest.raises(ValueError, match="at least 1"):
        bus.polled(bus.keys.voice_command, VoiceCommand, size=0)


def test_health_queryable_and_liveliness(bus: ServiceContext, peer: ServiceContext) -> None:
    peer.set_status(HealthStatus.DEGRADED, device="camera:0 missing")
    # the queryable is declared with the context; retry until the declaration has reached the router
    health = cast(Health, wait_for(lambda: bus.query_health("peer", timeout=1)))
    assert health.service == "peer" and health.status is HealthStatus.DEGRADED
    assert health.detail["device"] == "camera:0 missing"
    assert wait_for(lambda: {"peer", "tester"} <= alive_services(bus))
    peer.close()
    wait_for(lambda: "peer" not in alive_services(bus), timeout=5)


def test_query_health_is_none_without_a_valid_answer(bus: ServiceContext, peer: ServiceContext) -> None:
    assert bus.query_health("nobody", timeout=0.3) is None
    liar = peer.session.declare_queryable(peer.keys.health("liar"), lambda q: q.reply(q.key_expr, b"not json"))
    try:
        wait_for(lambda: any(r.ok is not None for r in bus.session.get(bus.keys.health("liar"), timeout=1)))
        assert bus.query_health("liar", timeout=1) is None
    finally:
        liar.undeclare()


def test_settings_from_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("ZENOH_CONFIG", raising=False)
    monkeypatch.delenv("HRI_ZENOH_CONNECT", raising=False)
    monkeypatch.delenv("HRI_ROBOT", raising=False)
    s = BusSettings.from_env()
    assert s.robot == "op2" and s.connect == ("tcp/127.0.0.1:7447",) and s.config_file is None
    conf = s.zenoh_config()
    assert conf.get_json("mode") == '"client"'
    assert conf.get_json("scouting/multicast/enabled") == "false"

    monkeypatch.setenv("HRI_ZENOH_CONNECT", "tcp/10.0.0.2:7447, tcp/10.0.0.3:7447")
    monkeypatch.setenv("HRI_ROBOT", "op2-b")
    s = BusSettings.from_env()
    assert s.connect == ("tcp/10.0.0.2:7447", "tcp/10.0.0.3:7447") and s.robot == "op2-b"

    cfg = tmp_path / "z.json5"
    cfg.write_text('{ mode: "peer", scouting: { multicast: { enabled: false } } }')
    monkeypatch.setenv("ZENOH_CONFIG", str(cfg))
    s = BusSettings.from_env()
    assert s.config_file == cfg and s.zenoh_config().get_json("mode") == '"peer"'

    monkeypatch.setenv("ZENOH_CONFIG", str(tmp_path / "missing.json5"))
    with pytest.raises(ConfigError, match="ZENOH_CONFIG"):
        BusSettings.from_env()
    monkeypatch.delenv("ZENOH_CONFIG")
    monkeypatch.setenv("HRI_ZENOH_CONNECT", "127.0.0.1:7447")
    with pytest.raises(ConfigError, match="no protocol"):
        BusSettings.from_env()
    monkeypatch.setenv("HRI_ZENOH_CONNECT", "tcp/127.0.0.1:7447")
    monkeypatch.setenv("HRI_ROBOT", "a/b")
    with pytest.raises(ConfigError, match="HRI_ROBOT"):
        BusSettings.from_env()


STUCK_SUBSCRIBER = """
import sys, threading, zenoh
from services.runtime import client_config

session = zenoh.open(client_config([sys.argv[1]]))
session.declare_subscriber(sys.argv[2], lambda _sample: threading.Event().wait())  # a terminal paused for good
print("reading no more", flush=True)
sys.stdin.read()
"""


def test_a_subscriber_that_stops_reading_holds_blocking_messages_back_only_briefly(router_endpoint: str,
                                                                                  keys: Keys) -> None:
    """Motion goals block rather than drop. A client that stops reading everything (an `hri spy` whose terminal
    is paused; here a process of its own) has its link filled by other traffic (large messages that may drop);
    the router then waits for room before it forwards a goal to anyone, with Zenoh's default for up to 5 s (about
    5.0 s here), and only then closes that link. Ours waits 0.25 s; asserted: no goal later than 3 s, room for a
    loaded machine's own delays and still well short of the default's 5 s."""
    stuck = subprocess.Popen([sys.executable, "-c", STUCK_SUBSCRIBER, router_endpoint, keys.all], cwd=ROOT,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    motion, publisher = (zenoh.open(client_config([router_endpoint])) for _ in range(2))
    late: dict[int, float] = {}
    sent = 0

    def goal(sample: zenoh.Sample) -> None:
        number, at = sample.payload.to_bytes().split()
        late[int(number)] = time.monotonic() - float(at)

    try:
        assert stuck.stdout is not None and "reading no more" in stuck.stdout.readline()
        motion.declare_subscriber(keys.motion_goal, goal)
        goals = publisher.declare_publisher(keys.motion_goal, congestion_control=zenoh.CongestionControl.BLOCK)
        images = publisher.declare_publisher(f"{keys.prefix}/test/image", congestion_control=zenoh.CongestionControl.DROP)
        # A subscriber's declaration reaches the router on its own link: on a loaded machine a goal sent at once
        # from another session could find no route yet and be dropped, which is not what this test is about
        # (measured: 7 of 40 first messages lost with 8 busy processes on 2 cores). Goal -1 until one arrives.
        wait_for(lambda: goals.put(f"-1 {time.monotonic():.6f}") or -1 in late, timeout=10, interval=0.05)
        image = b"x" * 65536
        end = time.monotonic() + 3.0
        for i in itertools.count():
            if time.monotonic() > end:
                break
            images.put(image)
            if i % 10 == 0:
                goals.put(f"{sent} {time.monotonic():.6f}")
                sent += 1
            time.sleep(0.002)
        # Generous: on a loaded 2-core machine (the whole suite on two workers) delivery itself can lag; the waiting
        # returns as soon as every goal is in, and the delay asserted below is what tells 0.25 s from Zenoh's 5 s.
        deadline = time.monotonic() + 30
        while not set(range(sent)) <= late.keys() and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        stuck.kill()
        stuck.wait()
        motion.close()
        publisher.close()
    lost = sorted(set(range(sent)) - late.keys())
    assert not lost, f"{len(lost)} of {sent} goals never arrived (numbers {lost[:10]}...)"
    worst = max(late[n] for n in range(sent))
    assert worst < 3.0, f"a goal waited {worst:.2f} s for a client that did not read ({sent} goals)"


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_service_stops_cleanly_on_signal(start_service, bus: ServiceContext, sig: signal.Signals) -> None:
    proc = start_service("speech")
    wait_for(lambda: "speech" in alive_services(bus), timeout=15)
    t0 = time.monotonic()
    proc.send_signal(sig)
    assert proc.wait(5) == 0
    assert time.monotonic() - t0 < 3
    assert b"stopped" in proc.log_path.read_bytes()
    wait_for(lambda: "speech" not in alive_services(bus), timeout=5)


BUSY_LOGGER = """
import sys
from services.runtime import run_service

def body(ctx):
    while not ctx.stopping.is_set():
        ctx.log.info("busy", pad="x" * 200)

sys.exit(run_service("speech", body))
"""


def test_a_service_writing_a_log_line_when_signalled_still_stops(router_endpoint: str, robot_id: str) -> None:
    """Its log goes to a pipe the test stops reading, so the service is blocked writing a line, holding the
    log's lock, when SIGTERM comes. A handler that logged there waited on that lock forever, and so did each
    later signal (seen with a service signalled as it logged a retry)."""
    proc = subprocess.Popen([sys.executable, "-c", BUSY_LOGGER], cwd=ROOT, env=service_env(router_endpoint, robot_id),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    assert proc.stderr is not None
    try:
        while b"busy" not in proc.stderr.readline():  # its body runs
            assert proc.poll() is None
        time.sleep(1.0)  # the pipe fills within milliseconds
        proc.send_signal(signal.SIGTERM)
        time.sleep(0.5)  # the handler has run
        _, tail = proc.communicate(timeout=10)  # drains the pipe; the process must exit
    finally:
        proc.kill()
    assert proc.returncode == 0
    assert b"stopping" in tail and tail.rstrip().endswith(b"service=speech") and b"stopped" in tail.splitlines()[-1]


STUBBORN = """
import sys, time
from services.runtime import run_service

def body(ctx):
    ctx.log.info("serving")
    while True:  # never looks at ctx.stopping
        time.sleep(0.05)

sys.exit(run_service("speech", body))
"""


def test_a_second_signal_ends_a_service_that_does_not_stop(router_endpoint: str, robot_id: str) -> None:
    proc = subprocess.Popen([sys.executable, "-c", STUBBORN], cwd=ROOT, env=service_env(router_endpoint, robot_id),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        lines, reader = read_lines(proc, stream="stderr")
        while "serving" not in lines.get(timeout=30):
            pass
        proc.send_signal(signal.SIGINT)
        while "stopping" not in lines.get(timeout=10):
            pass
        assert proc.poll() is None  # the body goes on
        proc.send_signal(signal.SIGINT)
        assert proc.wait(10) == 128 + signal.SIGINT
        reader.join(5)
        assert "second signal, exiting now" in "".join(lines.queue)
    finally:
        proc.kill()


def test_service_without_a_router_retries_and_still_stops(robot_id: str) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"  # nobody listens here
    proc = subprocess.Popen([sys.executable, "-m", "services.speech"], cwd=ROOT,
                            env=service_env(endpoint, robot_id), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    lines, reader = read_lines(proc)
    early = [lines.get(timeout=30)]  # signalled as it logs its first retry, which once hung it (above)
    while "no zenoh router yet" not in early[-1]:
        early.append(lines.get(timeout=30))
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=10)
    reader.join(5)
    assert proc.returncode == 0
    assert endpoint in early[-1]


def test_a_service_stuck_opening_its_session_still_stops_on_sigterm(robot_id: str) -> None:
    """A router that accepts the connection and never answers holds `zenoh.open` for about ten
    seconds; SIGTERM must not wait for it (a container's stop would end in SIGKILL)."""
    with socket.create_server(("127.0.0.1", 0)) as silent:
        endpoint = f"tcp/127.0.0.1:{silent.getsockname()[1]}"
        proc = subprocess.Popen([sys.executable, "-m", "services.speech"], cwd=ROOT,
                                env=service_env(endpoint, robot_id), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT)
        silent.settimeout(30)
        held, _ = silent.accept()  # the service is in `zenoh.open` now (a fixed wait could signal it earlier)
        time.sleep(0.5)
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=15)
        took = time.monotonic() - t0
        held.close()
    assert proc.returncode == 0
    assert b"stopped before the session opened" in out
    assert took < 6, f"took {took:.1f} s to stop"  # about 2 s; 10 s when SIGTERM waited for zenoh.open


@pytest.mark.parametrize(("name", "value"), [("HRI_LOG_LEVEL", "loud"), ("HRI_LOG_FORMAT", "xml")])
def test_a_bad_log_setting_is_refused_at_start(robot_id: str, name: str, value: str) -> None:
    env = service_env(f"tcp/127.0.0.1:{free_port()}", robot_id, **{name: value})
    out = subprocess.run([sys.executable, "-m", "services.speech"], check=False, cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=30)
    assert out.returncode == 2
    assert f"{name}={value!r}" in out.stderr and "use one of" in out.stderr


def test_bad_configuration_is_a_clear_error(router_endpoint: str, robot_id: str) -> None:
    env = service_env(router_endpoint, robot_id, HRI_ZENOH_CONNECT="localhost:7447")
    out = subprocess.run([sys.executable, "-m", "services.vision"], cwd=ROOT, env=env,
                         capture_output=True, timeout=30)
    assert out.returncode == 2
    assert b"no protocol" in out.stderr
