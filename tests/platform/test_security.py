"""Identities, the access table and a real secured router (zenoh-python, in its own process):
who can open a session, and what the router lets through."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh
from cryptography import x509
from cryptography.x509.oid import NameOID

from schemas.access import (
    ACCESS,
    IDENTITIES,
    OBSERVER,
    OPERATOR,
    RATE_LIMITS,
    Kind,
    access_control,
    downsampling,
    may_put,
    owners,
    qos_overwrites,
)
from schemas.keys import SERVICES, Keys
from schemas.messages import Command, Decision, Reason, Situation, Verdict, VoiceCommand
from services.cli import keys as deployment_keys
from services.cli.router import free_port, wait_listening
from services.runtime import (
    ConfigError,
    Credentials,
    RouterSecurity,
    ServiceContext,
    client_config,
    encode,
    router_config,
)
from services.runtime.config import check_listen
from services.voice.pacing import CommandPacer
from tests.conftest import ROOT, wait_for


# ---------------------------------------------------------------------------------------- the table
def topic_keys(keys: Keys) -> set[str]:
    """Every topic key of the contract (the `Keys` properties), relative to `hri/<robot>/`."""
    out = set()
    for name in dir(Keys):
        attr = getattr(Keys, name)
        if isinstance(attr, property) and name not in ("prefix", "all", "health_all", "alive_all"):
            value = getattr(keys, name)
            out.add(value[len(keys.prefix) + 1 :])
    return out


def test_every_key_of_the_contract_has_a_row_and_an_owner() -> None:
    held: dict[tuple[str, Kind], set[str]] = {}
    for row in ACCESS:
        held.setdefault((row.key, row.kind), set()).update(row.owners)
    for key in topic_keys(Keys("op2")):
        kind = Kind.QUERYABLE if key.startswith("reasoner/") and key != "reasoner/decision" else Kind.TOPIC
        assert held.get((key, kind)), f"{key} is in schemas/keys.py but has no owner in the access table"
    for name in SERVICES:
        assert held[(f"{name}/health", Kind.QUERYABLE)] == {name}
        assert held[(f"alive/{name}", Kind.TOKEN)] == {name}
        assert owners(f"{name}/health") == ()  # not a topic: nobody puts it


def test_only_the_owners_may_put_what_moves_the_robot() -> None:
    for identity in IDENTITIES:
        assert may_put(identity, "motion/goal") == (identity == "reasoner")
        assert may_put(identity, "speech/say") == (identity == "reasoner")
        assert may_put(identity, "voice/command") == (identity in ("voice", OPERATOR))
        assert may_put(identity, "vision/marks") == (identity in ("vision", OPERATOR))
    assert not may_put(OPERATOR, "voice/command", operator_writes=False)
    assert not any(may_put(OBSERVER, row.key) for row in ACCESS)


def test_generated_rules_deny_by_default_and_name_only_the_table() -> None:
    acl = access_control("r2", tls=True)
    assert acl["enabled"] and acl["default_permission"] == "deny"
    assert all(r["permission"] == "allow" for r in acl["rules"])
    puts = {
        r["id"].split(":")[0]: r["key_exprs"]
        for r in acl["rules"]
        if r["messages"] == ["put"] and r["flows"] == ["ingress"]
    }
    assert puts["reasoner"] == ["hri/r2/reasoner/decision", "hri/r2/motion/goal", "hri/r2/speech/say"]
    assert OBSERVER not in puts
    soar_askers = [
        r["id"].split(":")[0]
        for r in acl["rules"]
        if r["messages"] == ["query"]
        and "hri/r2/reasoner/soar" in r["key_exprs"]
        and r["flows"] == ["ingress"]
    ]
    assert soar_askers == [OPERATOR]
    tls_subjects = [s for s in acl["subjects"] if s["link_protocols"] == ["tls"]]
    assert all(s["usernames"] == s["cert_common_names"] for s in tls_subjects)
    withheld = access_control("r2", operator_writes=False)
    assert not any(r["id"].startswith("operator:put:ingress") for r in withheld["rules"])


# ---------------------------------------------------------------------------------------- keys on disk
@pytest.fixture(scope="module")
def keys_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("deployment") / "keys"
    deployment_keys.init(folder)
    return folder


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_secrets_are_owner_only_and_certificates_name_their_identity(keys_dir: Path) -> None:
    assert mode(keys_dir) == 0o700 and mode(keys_dir / "ca" / "ca.key") == 0o600
    assert mode(keys_dir / "router" / "dictionary") == 0o600
    ca = x509.load_pem_x509_certificate((keys_dir / "ca" / "ca.pem").read_bytes())
    users = set()
    for identity in IDENTITIES:
        folder = keys_dir / identity
        assert mode(folder / "password") == 0o600 and mode(folder / "key.pem") == 0o600
        cert = x509.load_pem_x509_certificate((folder / "cert.pem").read_bytes())
        assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == identity
        cert.verify_directly_issued_by(ca)
        users.add(Credentials.load(folder).user)
    assert users == set(IDENTITIES)
    lines = (keys_dir / "router" / "dictionary").read_text().split()
    assert len(lines) == len(IDENTITIES) and len({line.split(":")[1] for line in lines}) == len(IDENTITIES)


def test_init_refuses_to_overwrite_and_rotate_replaces_one_secret(tmp_path: Path) -> None:
    folder = tmp_path / "keys"
    deployment_keys.init(folder)
    with pytest.raises(ConfigError, match="already holds identities"):
        deployment_keys.init(folder)
    before = {i: (folder / i / "password").read_text() for i in IDENTITIES}
    deployment_keys.rotate(folder, "voice")
    after = {i: (folder / i / "password").read_text() for i in IDENTITIES}
    assert after["voice"] != before["voice"]
    assert {i: v for i, v in after.items() if i != "voice"} == {
        i: v for i, v in before.items() if i != "voice"
    }
    assert f"voice:{after['voice'].strip()}" in (folder / "router" / "dictionary").read_text()


def test_a_readable_secret_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "keys"
    deployment_keys.init(folder, identities=["observer"])
    os.chmod(folder / "observer" / "password", 0o644)
    with pytest.raises(ConfigError, match="chmod 600"):
        Credentials.load(folder / "observer")


def test_a_secure_router_listens_on_other_interfaces_only_with_tls(keys_dir: Path) -> None:
    security = RouterSecurity(keys_dir)
    check_listen(["tcp/127.0.0.1:7447", "tcp/[::1]:7447", "tls/0.0.0.0:7448"], security)
    with pytest.raises(ConfigError, match="not loopback"):
        check_listen(["tcp/0.0.0.0:7447"], security)
    check_listen(["tcp/0.0.0.0:7447"], None)  # open on purpose
    with pytest.raises(ConfigError, match="not loopback"):
        router_config(["tcp/192.168.1.5:7447"], security)


# ---------------------------------------------------------------------------------------- a real router
@pytest.fixture(scope="module")
def router_process(keys_dir: Path) -> Iterator[tuple[subprocess.Popen[bytes], str, str]]:
    """A secured router process (tcp on loopback and tls) for robot `sec`: the process, its tcp and tls endpoints."""
    port, tls_port = free_port(), free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services.cli.router",
            "--keys-dir",
            str(keys_dir),
            "--robot",
            "sec",
            "--listen",
            f"tcp/127.0.0.1:{port}",
            "--listen",
            f"tls/127.0.0.1:{tls_port}",
        ],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        wait_listening(port)
        wait_listening(tls_port)
        yield proc, f"tcp/127.0.0.1:{port}", f"tls/localhost:{tls_port}"
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)


@pytest.fixture(scope="module")
def secure_router(router_process: tuple[subprocess.Popen[bytes], str, str]) -> tuple[str, str]:
    """The secured router's (tcp, tls) endpoints."""
    return router_process[1], router_process[2]


def open_as(endpoint: str, folder: Path | None) -> zenoh.Session:
    return zenoh.open(client_config([endpoint], Credentials.load(folder) if folder else None))


def refused(endpoint: str, folder: Path | None) -> bool:
    try:
        open_as(endpoint, folder).close()
    except zenoh.ZError:
        return True
    return False


def test_no_or_wrong_credentials_open_no_session(
    secure_router: tuple[str, str], keys_dir: Path, tmp_path: Path
) -> None:
    tcp, tls = secure_router
    assert refused(tcp, None)
    other = tmp_path / "other"
    deployment_keys.init(other)  # another deployment's identities: right names, wrong secrets
    assert refused(tcp, other / "operator")
    assert refused(tls, other / "operator")
    open_as(tcp, keys_dir / "operator").close()
    open_as(tls, keys_dir / "operator").close()


def test_hri_says_in_one_line_why_it_has_no_session(secure_router: tuple[str, str], tmp_path: Path) -> None:
    env = {**os.environ, "HRI_KEYS_DIR": str(tmp_path / "none")}
    env.pop("HRI_CREDENTIALS", None)
    out = subprocess.run(
        [sys.executable, "-m", "services.cli", "status", "--connect", secure_router[0]],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [
        f"error: the router at {secure_router[0]} refused an anonymous session; it requires credentials: "
        "set HRI_CREDENTIALS=<keys dir>/<identity> (see `hri keys init`)"
    ]


class Inbox:
    def __init__(self, session: zenoh.Session, key: str) -> None:
        self.got: list[bytes] = []
        self.sub = session.declare_subscriber(key, lambda s: self.got.append(s.payload.to_bytes()))


@pytest.mark.parametrize("link", ["tcp", "tls"])
def test_the_router_drops_puts_the_table_does_not_allow(
    secure_router: tuple[str, str], keys_dir: Path, link: str
) -> None:
    endpoint = secure_router[0] if link == "tcp" else secure_router[1]
    key = Keys("sec").motion_goal
    motion = open_as(endpoint, keys_dir / "motion")
    sessions = {
        name: open_as(endpoint, keys_dir / name) for name in ("reasoner", "observer", "vision", "operator")
    }
    try:
        inbox = Inbox(motion, key)
        pubs = {name: s.declare_publisher(key) for name, s in sessions.items()}
        # Every publisher learns that motion subscribes: the clients do send, the router decides.
        wait_for(lambda: all(p.matching_status.matching for p in pubs.values()), timeout=5)
        for _ in range(3):
            for name, pub in pubs.items():
                pub.put(name.encode())
        wait_for(lambda: inbox.got.count(b"reasoner") == 3, timeout=5)
        time.sleep(0.3)
        assert sorted(set(inbox.got)) == [b"reasoner"]
    finally:
        for s in (motion, *sessions.values()):
            s.close()


def test_the_router_limits_the_rate_of_one_session_on_the_reasoners_inputs(
    secure_router: tuple[str, str], keys_dir: Path
) -> None:
    """A flood from one allowed session is cut to `RATE_LIMITS` at the router; another session's
    put on the same key still gets through, and motion goals are never limited."""
    tcp, _tls = secure_router
    k = Keys("sec")
    reasoner, voice, operator, motion = (open_as(tcp, keys_dir / n) for n in ("reasoner", "voice", "operator",
                                                                            "motion"))
    try:
        commands, goals = Inbox(reasoner, k.voice_command), Inbox(motion, k.motion_goal)
        flood, person = voice.declare_publisher(k.voice_command), operator.declare_publisher(k.voice_command)
        goal = reasoner.declare_publisher(k.motion_goal, congestion_control=zenoh.CongestionControl.BLOCK)
        wait_for(lambda: flood.matching_status.matching and goal.matching_status.matching, timeout=5)
        t0 = time.monotonic()
        while (elapsed := time.monotonic() - t0) < 1.0:
            flood.put(b"flood")
        for _ in range(2000):  # a burst far above every input limit
            goal.put(b"goal")
        person.put(b"stop")
        wait_for(lambda: b"stop" in commands.got and len(goals.got) == 2000, timeout=10)
        time.sleep(0.3)
        window = time.monotonic() - t0  # the flood was sent in the first second, and drained since
        flooded = commands.got.count(b"flood")
        assert elapsed >= 1.0 and 0 < flooded <= RATE_LIMITS["voice/command"] * window + 10, flooded
    finally:
        for s in (reasoner, voice, operator, motion):
            s.close()


@pytest.mark.parametrize("paced", [False, True])
def test_commands_put_while_the_router_is_held_back_all_arrive_when_paced(
    router_process: tuple[subprocess.Popen[bytes], str, str], keys_dir: Path, paced: bool
) -> None:
    """Three commands put 30 ms apart reach a router that the scheduler held back together, and its rate limit keeps
    only the first. Paced by the reasoner's answers (`services.voice.pacing`, the voice service's way, over the
    access table's read right on decisions), each is put only once the router has passed the one before: all
    three arrive."""
    proc, tcp, _tls = router_process
    k = Keys("sec")
    reasoner, voice = open_as(tcp, keys_dir / "reasoner"), open_as(tcp, keys_dir / "voice")
    try:
        got: list[VoiceCommand] = []
        answers = reasoner.declare_publisher(k.reasoner_decision)

        def answer(sample: zenoh.Sample) -> None:  # the reasoner: a decision for each command, caused by it
            command = VoiceCommand.model_validate_json(sample.payload.to_bytes())
            got.append(command)
            answers.put(encode(Decision(command=command.command, verdict=Verdict.OBEY, reason=Reason.OK,
                                        situation=Situation.SAFE, cause_stamp=command.stamp)))

        _sub = reasoner.declare_subscriber(k.voice_command, answer)
        decisions = ServiceContext("voice", voice, k).polled(k.reasoner_decision, Decision)  # as the service does
        pacer = CommandPacer(lambda: [d.cause_stamp for d in decisions()])
        pub = voice.declare_publisher(k.voice_command)
        wait_for(lambda: pub.matching_status.matching, timeout=5)

        def say(word: str) -> None:
            if paced:
                pacer.turn()
            command = VoiceCommand(command=Command(word), text=word, confidence=1.0, engine="test")
            pacer.put(command.stamp)
            pub.put(encode(command))

        say("stand")  # the reasoner is there and answers: pacing begins
        wait_for(lambda: len(got) == 1, timeout=5)
        time.sleep(0.1)
        os.kill(proc.pid, signal.SIGSTOP)  # held back for 300 ms: less than the pacer's wait for an answer (0.5 s)
        resume = threading.Timer(0.3, os.kill, (proc.pid, signal.SIGCONT))
        resume.start()
        try:
            for word in ("yes", "no", "yes"):
                say(word)
                time.sleep(0.03)
        finally:
            resume.join()
            os.kill(proc.pid, signal.SIGCONT)
        time.sleep(1.0)
        words = [c.command.value for c in got[1:] if c.command is not None]
        if paced:
            assert words == ["yes", "no", "yes"] and pacer.held >= 1 and pacer.unanswered == 0, words
        else:  # the first, and whatever the scheduler let come after the router woke
            assert words[0] == "yes" and len(words) < 3, words
    finally:
        reasoner.close()
        voice.close()


def test_the_router_sets_the_priority_of_the_reasoners_inputs(secure_router: tuple[str, str], keys_dir: Path) -> None:
    """Whatever priority a publisher asks for, commands arrive at `data` and marks above them."""
    tcp, _tls = secure_router
    k = Keys("sec")
    reasoner, voice, vision = (open_as(tcp, keys_dir / n) for n in ("reasoner", "voice", "vision"))
    try:
        got: dict[str, zenoh.Priority] = {}
        _subs = [reasoner.declare_subscriber(key, lambda s: got.setdefault(str(s.key_expr), s.priority))
                 for key in (k.voice_command, k.vision_marks)]  # held: a dropped subscriber is undeclared
        command = voice.declare_publisher(k.voice_command, priority=zenoh.Priority.REAL_TIME)
        marks = vision.declare_publisher(k.vision_marks, priority=zenoh.Priority.DATA_LOW)
        wait_for(lambda: command.matching_status.matching and marks.matching_status.matching, timeout=5)
        command.put(b"go")
        marks.put(b"{}")
        wait_for(lambda: len(got) == 2, timeout=5)
        assert got == {k.voice_command: zenoh.Priority.DATA, k.vision_marks: zenoh.Priority.INTERACTIVE_HIGH}
    finally:
        for s in (reasoner, voice, vision):
            s.close()


def test_a_stolen_password_without_its_certificate_gets_no_rights(
    secure_router: tuple[str, str], keys_dir: Path, tmp_path: Path
) -> None:
    """On TLS the subject is the user name AND the certificate's common name: the reasoner's
    password presented with the vision certificate opens a session that may do nothing."""
    mixed = tmp_path / "mixed"
    mixed.mkdir(mode=0o700)
    for name in ("user", "password"):
        (mixed / name).write_bytes((keys_dir / "reasoner" / name).read_bytes())
    for name in ("cert.pem", "key.pem", "ca.pem"):
        (mixed / name).write_bytes((keys_dir / "vision" / name).read_bytes())
    for name in ("password", "key.pem"):
        os.chmod(mixed / name, 0o600)
    key = Keys("sec").motion_goal
    motion = open_as(secure_router[1], keys_dir / "motion")
    thief = open_as(secure_router[1], mixed)
    try:
        inbox = Inbox(motion, key)
        pub = thief.declare_publisher(key)
        time.sleep(0.5)
        for _ in range(3):
            pub.put(b"thief")
        time.sleep(0.5)
        assert inbox.got == []
    finally:
        thief.close()
        motion.close()


def test_observer_reads_everything_and_queries_health(secure_router: tuple[str, str], keys_dir: Path) -> None:
    keys = Keys("sec")
    tcp = secure_router[0]
    vision, observer, reasoner = (open_as(tcp, keys_dir / n) for n in ("vision", "observer", "reasoner"))
    try:
        token = vision.liveliness().declare_token(keys.alive("vision"))
        vision.declare_queryable(keys.health("vision"), lambda q: q.reply(keys.health("vision"), b"ok"))
        inbox = Inbox(observer, keys.all)
        pub = vision.declare_publisher(keys.vision_marks)
        wait_for(lambda: pub.matching_status.matching, timeout=5)
        pub.put(b"m")
        wait_for(lambda: inbox.got == [b"m"], timeout=5)
        health = [r.ok.payload.to_bytes() for r in observer.get(keys.health_all, timeout=2) if r.ok]
        assert health == [b"ok"]
        alive = [str(r.ok.key_expr) for r in observer.liveliness().get(keys.alive_all, timeout=2) if r.ok]
        assert alive == [keys.alive("vision")]
        # The reasoner reads marks but may not ask for another service's health nor run Soar on itself.
        assert [r for r in reasoner.get(keys.health("vision"), timeout=1) if r.ok] == []
        token.undeclare()
    finally:
        for s in (vision, observer, reasoner):
            s.close()


def test_the_voice_service_may_ask_the_speech_services_health_and_no_other(secure_router: tuple[str, str],
                                                                            keys_dir: Path) -> None:
    """At start-up the voice service asks whether the robot is in the middle of a sentence (`HEALTH_ASKERS`)."""
    keys = Keys("sec")
    tcp = secure_router[0]
    speech, vision, voice = (open_as(tcp, keys_dir / n) for n in ("speech", "vision", "voice"))
    try:
        for name, session in (("speech", speech), ("vision", vision)):
            key = keys.health(name)
            session.declare_queryable(key, lambda q, key=key: q.reply(key, b"ok"))
        wait_for(lambda: [r for r in voice.get(keys.health("speech"), timeout=1) if r.ok], timeout=5)
        assert [r for r in voice.get(keys.health("vision"), timeout=1) if r.ok] == []
    finally:
        for s in (speech, vision, voice):
            s.close()


def test_credentials_still_join_an_open_router(router_endpoint: str, keys_dir: Path) -> None:
    """An open router refuses clients that offer credentials; the runtime then joins it anonymously."""
    from services.runtime import BusSettings, open_session
    from services.runtime.logs import get_logger

    settings = BusSettings(connect=(router_endpoint,), credentials=Credentials.load(keys_dir / "observer"))
    open_session(settings, get_logger("test"), attempts=2).close()


# ---------------------------------------------------------------------------------------- flooding
def test_a_bounded_subscription_drops_the_oldest_and_counts(router_endpoint: str, keys: Keys) -> None:
    from schemas import VoiceCommand
    from services.runtime import ServiceContext

    bus = ServiceContext("bus", zenoh.open(client_config([router_endpoint])), keys)
    peer = ServiceContext("peer", zenoh.open(client_config([router_endpoint])), keys)
    try:
        got: list[int] = []
        gate = threading.Event()

        def slow(msg: VoiceCommand) -> None:
            gate.wait(10)
            got.append(msg.seq)

        bus.subscribe(keys.voice_command, VoiceCommand, slow, queue=4)
        pub = peer.publisher(keys.voice_command, VoiceCommand, block=True)
        wait_for(lambda: pub.matched, timeout=5)
        for _ in range(50):
            pub.put(VoiceCommand(command=None, text="x", confidence=0.5, engine="flood"))
        wait_for(lambda: sum(bus.drops.values()) >= 45, timeout=5)
        gate.set()
        wait_for(lambda: len(got) + bus.drops["voice/command"] == 50, timeout=5)
        assert len(got) <= 5 and got[-1] == 50  # the newest survive
        health = bus.health()
        assert health.detail["dropped"] == {"voice/command": 50 - len(got)}
        assert health.received == len(got)  # counted when validated, after the queue
    finally:
        peer.close()
        bus.close()


def test_router_config_file_is_a_zenoh_configuration_with_the_rules(keys_dir: Path, tmp_path: Path) -> None:
    """`hri keys router-config` (for zenohd): the same authentication and rules, paths as mounted."""
    text = deployment_keys.router_config_file(RouterSecurity(keys_dir, robot="r9"), ["tls/0.0.0.0:7447"],
                                              "/etc/hri/router")
    path = tmp_path / "router.json5"
    path.write_text(text)
    zenoh.Config.from_file(str(path))  # zenoh accepts it
    conf = json.loads(text)
    assert conf["mode"] == "router" and conf["listen"]["endpoints"] == ["tls/0.0.0.0:7447"]
    assert conf["transport"]["auth"]["usrpwd"]["dictionary_file"] == "/etc/hri/router/dictionary"
    assert conf["transport"]["link"]["tls"]["enable_mtls"] is True
    assert conf["transport"]["link"]["tx"]["queue"]["congestion_control"]["block"]["wait_before_close"] == 250_000
    assert conf["access_control"] == access_control("r9", tls=True)
    assert conf["downsampling"] == downsampling("r9")
    assert conf["qos"]["network"] == qos_overwrites("r9")
    assert "password" not in text  # the dictionary stays a file; no secret is copied into the config
