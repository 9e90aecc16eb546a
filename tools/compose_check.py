"""The compose stack on a real Docker engine, checked end to end from the host (run by tools/compose-check).

Makes the deployment's identities (`hri keys init`, in a temporary folder), builds the project image
once, brings docker-compose.yml up under its own project name (its own volume, image tag and router
port picked free on 127.0.0.1, so a user's own stack is never touched), waits until every service
container reports healthy, checks that a session without credentials is refused, then runs the paper's
scenario against the stack from the host (status as the observer, the runner as the operator, over
mutual TLS):
spoken commands as WAV files written into the voice container's spool folder, cards shown to the
synthetic camera through the bus (the message `hri send scene` publishes), and the refused "go" checked
with its spoken reply fetched from the speech container as a WAV. Tears the stack down and prints the
times and the image size. Exit status: 0 pass, 1 fail.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import uuid
import wave
from collections.abc import Callable
from pathlib import Path
from typing import IO

import zenoh

from schemas.keys import SERVICES, Keys
from schemas.messages import SpeechRequest, Verdict
from services.cli import keys as deployment_keys
from services.cli.recorder import Recorder
from services.cli.router import free_port
from services.cli.runner import ScenarioRunner, StepResult
from services.cli.scenario import load
from services.cli.utterance import speak_into
from services.runtime import ConfigError, Credentials, ServiceContext, client_config
from services.speech.player import file_stem

ROOT = Path(__file__).resolve().parents[1]
PROJECT = f"hri-check-{os.getpid()}"  # its own containers, network and volume: checks may run side by side
IMAGE = f"hri-op2:check-{os.getpid()}"  # and its own image tag (HRI_IMAGE), removed at the end
CONTAINER_UID = 10001  # the image's user, who must own the secrets mounted into the containers
SPOOL = "/var/lib/hri/voice-spool"
SPEECH = "/var/lib/hri/speech"
REFUSAL = "Sorry, I cannot do it."
BUILD_LOG = Path(tempfile.gettempdir()) / "hri-compose-check-build.log"
PROXY_VARS = ("HTTP_PROXY", "HTTPS_PROXY", "NO_PROXY", "http_proxy", "https_proxy", "no_proxy")


def log(message: str) -> None:
    print(f"[compose-check] {message}", flush=True)


class Stack:
    """`docker compose` on this checkout's compose file, under the check's own project name."""

    def __init__(self, router_port: int, keys: Path) -> None:
        self.router_port = router_port
        self.keys = keys
        # The stack's defaults, whatever this shell has set (HRI_VOICE_SOURCE=mic, say).
        self.env = {k: v for k, v in os.environ.items() if not k.startswith(("HRI_", "ZENOH_"))}
        self.env.update(HRI_ROUTER_PORT=str(router_port), HRI_IMAGE=IMAGE, HRI_KEYS_DIR=str(keys))

    def run(self, *args: str, input: bytes | None = None, check: bool = True, capture: bool = False,
            output: IO[bytes] | None = None, timeout: float = 900) -> subprocess.CompletedProcess[bytes]:
        """`docker compose ARGS`; its output captured, sent to `output`, or (neither) shown."""
        cmd = ["docker", "compose", "-p", PROJECT, "-f", str(ROOT / "docker-compose.yml"), *args]
        out = subprocess.run(cmd, input=input, env=self.env, cwd=ROOT, timeout=timeout, check=False,
                             stdout=subprocess.PIPE if capture else output,
                             stderr=subprocess.PIPE if capture else (subprocess.STDOUT if output else None))
        if check and out.returncode != 0:
            detail = out.stderr.decode(errors="replace").strip()[-2000:] if capture else ""
            where = f" (its output: {output.name})" if output else ""
            raise RuntimeError(f"`docker compose {' '.join(args)}` exited {out.returncode}{where} {detail}")
        return out

    def containers(self) -> dict[str, dict[str, str]]:
        out = self.run("ps", "--all", "--format", "json", capture=True).stdout.decode()
        rows = [json.loads(line) for line in out.splitlines() if line.strip()]
        if len(rows) == 1 and isinstance(rows[0], list):  # older Compose prints one JSON array
            rows = rows[0]
        return {r["Service"]: r for r in rows}

    def wait_healthy(self, timeout: float) -> list[str]:
        """Wait until the five services are healthy and the router runs; returns what is not (empty: all)."""
        deadline = time.monotonic() + timeout
        while True:
            rows = self.containers()
            bad = [f"{name}: {rows[name]['Status'] if name in rows else 'no container'}"
                   for name in SERVICES if rows.get(name, {}).get("Health") != "healthy"]
            if rows.get("zenoh", {}).get("State") != "running":
                bad.append(f"zenoh: {rows.get('zenoh', {}).get('Status', 'no container')}")
            if not bad or time.monotonic() > deadline:
                return bad
            time.sleep(2)

    def put_wav(self, wav: bytes) -> str:
        """Drop one WAV into the voice container's spool folder, atomically (as `speak_into` does)."""
        dest = f"{SPOOL}/{uuid.uuid4().hex[:12]}.wav"
        self.run("exec", "-T", "voice", "sh", "-c", 'cat > "$1.tmp" && mv "$1.tmp" "$1"', "sh", dest,
                 input=wav, timeout=60)
        return dest

    def fetch(self, service: str, path: str, dest: Path, timeout: float = 15) -> bool:
        """Copy a file out of a container once it exists (False if it never appears)."""
        deadline = time.monotonic() + timeout
        while self.run("exec", "-T", service, "test", "-s", path, check=False, capture=True).returncode != 0:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.5)
        time.sleep(0.5)  # the speech service writes the file, then waits out its duration
        self.run("cp", f"{service}:{path}", str(dest), capture=True)
        return True


class ComposeRunner(ScenarioRunner):
    """The scenario runner, speaking into the voice container's spool instead of a local folder."""

    def __init__(self, ctx: ServiceContext, rec: Recorder, stack: Stack, tmp: Path) -> None:
        super().__init__(ctx, rec, tmp)
        self.stack = stack

    def speak(self, words: str) -> None:
        local = speak_into(self.spool, words, voice=self.voice)  # synthesised here, decoded in there
        self.stack.put_wav(local.read_bytes())
        local.unlink()


def timed(what: str, times: dict[str, float], fn: Callable[[], object]) -> object:
    t0 = time.monotonic()
    try:
        return fn()
    finally:
        times[what] = time.monotonic() - t0


def run_scenario(stack: Stack, tmp: Path, problems: list[str]) -> list[StepResult]:
    """The paper's scenario from the host, then the refusal's WAV out of the speech container."""
    endpoint = f"tls/localhost:{stack.router_port}"  # the stack's router takes mutual TLS only
    try:
        zenoh.open(client_config([endpoint])).close()
        problems.append("the stack's router accepted a session without credentials")
    except zenoh.ZError:
        log("a session without credentials is refused")
    observer = {**os.environ, "HRI_CREDENTIALS": str(stack.keys / "observer")}
    observer.pop("ZENOH_CONFIG", None)
    status = subprocess.run([sys.executable, "-m", "services.cli", "status", "--json", "--connect", endpoint],
                            capture_output=True, text=True, timeout=60, cwd=ROOT, check=False, env=observer)
    rows = json.loads(status.stdout or "{}")
    not_ok = [n for n in SERVICES if not (rows.get(n, {}).get("alive")
                                          and (rows[n].get("health") or {}).get("status") == "ok")]
    if status.returncode != 0 or not_ok:
        problems.append(f"`hri status` from the host: not alive and ok: {', '.join(not_ok) or '?'}")
    log(f"hri status --connect {endpoint} (as the observer): " + ", ".join(
        f"{n} {(rows.get(n, {}).get('health') or {}).get('status', 'absent')}" for n in SERVICES))
    operator = Credentials.load(stack.keys / "operator")  # the scenario runner sends as the operator
    ctx = ServiceContext("compose-check", zenoh.open(client_config([endpoint], operator)), Keys("op2"))
    try:
        rec = Recorder(ctx)
        runner = ComposeRunner(ctx, rec, stack, tmp / "spool")
        missing = runner.wait_ready(timeout=120)
        if missing:
            problems.append(f"the stack is not ready for the scenario: {', '.join(missing)}")
            return []
        t0 = time.monotonic()

        def on_step(r: StepResult) -> None:
            outcome = "ok" if r.ok else "FAIL: " + "; ".join(r.problems)
            log(f"  step {r.index:>2} {r.step.label():<14} {outcome}")

        results = runner.run(load("paper"), on_step)
        problems += [f"step {r.index} {r.step.label()}: {'; '.join(r.problems)}" for r in results if not r.ok]
        refused = [r for r in results if r.decision and r.decision.verdict is Verdict.REFUSE]
        if not refused:
            problems.append('no "go" was refused')
        requests = [m for m in rec.since(t0, "say") if isinstance(m, SpeechRequest) and m.text == REFUSAL]
        if not requests:
            problems.append(f'the reasoner never asked to say "{REFUSAL}"')
            return results
        wav = tmp / "refusal.wav"
        if not stack.fetch("speech", f"{SPEECH}/{file_stem(requests[0].id)}.wav", wav):
            problems.append(f"no WAV in the speech container for request {requests[0].id}")
            return results
        with wave.open(str(wav)) as w:
            seconds = w.getnframes() / w.getframerate()
            log(f'refusal "{REFUSAL}": {file_stem(requests[0].id)}.wav from the speech container, '
                f"{seconds:.2f} s at {w.getframerate()} Hz")
        if seconds < 0.5:
            problems.append(f"the refusal WAV is only {seconds:.2f} s long")
        return results
    finally:
        ctx.close()


def image_size_mb() -> float:
    out = subprocess.run(["docker", "image", "inspect", "-f", "{{.Size}}", IMAGE], capture_output=True,
                         text=True, check=False)
    return int(out.stdout.strip() or 0) / 1e6


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cached", action="store_true", help="let the build reuse Docker's layer cache")
    parser.add_argument("--keep", action="store_true", help="leave the stack running (tear down yourself)")
    parser.add_argument("--vosk-model-url", default=os.environ.get("VOSK_MODEL_URL", ""),
                        help="build arg VOSK_MODEL_URL (default: empty, no vosk model: no model URL may be "
                             "reachable; the stack's default engine, pocketsphinx, ships its own)")
    parser.add_argument("--healthy-timeout", type=float, default=300.0)
    args = parser.parse_args()
    keys_root = Path(tempfile.mkdtemp(prefix="hri-compose-keys-"))
    stack = Stack(free_port(), keys_root / "keys")
    times: dict[str, float] = {}
    problems: list[str] = []
    results: list[StepResult] = []
    build_args = ["--build-arg", f"VOSK_MODEL_URL={args.vosk_model_url}"]
    build_args += [a for v in PROXY_VARS if v in os.environ for a in ("--build-arg", v)]
    log(f"building {IMAGE} once for the five services{'' if args.cached else ' (no layer cache)'}, "
        f"log in {BUILD_LOG}; vosk model: {args.vosk_model_url or 'skipped (no --vosk-model-url)'}")
    try:
        # The deployment's identities, as `sudo hri keys init --keys-dir ... --container-uid 10001` makes them.
        deployment_keys.init(stack.keys)
        deployment_keys.hand_to_containers(stack.keys, CONTAINER_UID)
        log(f"identities made in {stack.keys} (router and services owned by uid {CONTAINER_UID})")
        stack.run("down", "--volumes", "--remove-orphans", capture=True)  # a fresh volume, as a new user
        with BUILD_LOG.open("wb") as build_log:
            no_cache = [] if args.cached else ["--no-cache"]
            timed("build", times, lambda: stack.run("build", *build_args, *no_cache, output=build_log))
        log(f"image {IMAGE}: {image_size_mb():.0f} MB")
        timed("up", times, lambda: stack.run("up", "-d", "--no-build", capture=True))
        bad = timed("healthy", times, lambda: stack.wait_healthy(args.healthy_timeout))
        if bad:
            problems.append("not healthy after {:.0f} s: {}".format(times["healthy"], "; ".join(bad)))
        else:
            log(f"every container healthy {times['up'] + times['healthy']:.1f} s after `up`")
            with tempfile.TemporaryDirectory(prefix="hri-compose-check-") as tmp:
                t0 = time.monotonic()
                results = run_scenario(stack, Path(tmp), problems)
                times["scenario"] = time.monotonic() - t0
    except (RuntimeError, subprocess.TimeoutExpired, ConfigError) as exc:
        problems.append(str(exc))
    finally:
        if problems:
            stack.run("logs", "--no-color", "--tail", "25", check=False)
        size = image_size_mb()
        if not args.keep:
            timed("down", times, lambda: stack.run("down", "--volumes", "--timeout", "15", check=False,
                                                    capture=True))
            subprocess.run(["docker", "image", "rm", IMAGE], capture_output=True, check=False)  # the tag only
            shutil.rmtree(keys_root, ignore_errors=True)
    passed = sum(r.ok for r in results)
    log("times: " + ", ".join(f"{k} {v:.1f} s" for k, v in times.items())
        + f"; image {size:.0f} MB; paper scenario {passed}/{len(results)} steps as expected")
    for p in problems:
        log(f"problem: {p}")
    log("PASS" if not problems else "FAIL")
    return 0 if not problems else 1


if __name__ == "__main__":
    sys.exit(main())
