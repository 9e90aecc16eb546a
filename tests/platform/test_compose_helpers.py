"""The Docker build's model fetcher and the router stand-in, run here without Docker."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import zenoh

from services.cli.router import free_port, wait_listening
from services.runtime import client_config
from tests.conftest import ROOT, wait_for

FETCH = ROOT / "docker" / "fetch-model.py"


def _model_zip(tmp_path: Path) -> tuple[Path, str]:
    archive = tmp_path / "model.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("vosk-model-tiny/am/final.mdl", b"weights")
        z.writestr("vosk-model-tiny/conf/model.conf", b"conf")
    return archive, hashlib.sha256(archive.read_bytes()).hexdigest()


def fetch(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(FETCH), *args], capture_output=True, text=True, timeout=30)


def test_the_model_is_unpacked_when_its_checksum_matches(tmp_path: Path) -> None:
    archive, digest = _model_zip(tmp_path)
    out = fetch(archive.as_uri(), digest, str(tmp_path / "model"))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "model" / "am" / "final.mdl").read_bytes() == b"weights"


def test_a_wrong_checksum_unpacks_nothing(tmp_path: Path) -> None:
    archive, _ = _model_zip(tmp_path)
    out = fetch(archive.as_uri(), "0" * 64, str(tmp_path / "model"))
    assert out.returncode == 1 and "expected " + "0" * 64 in out.stderr
    assert not (tmp_path / "model").exists()


def test_an_empty_url_skips_the_model(tmp_path: Path) -> None:
    out = fetch("", "", str(tmp_path / "model"))
    assert out.returncode == 0 and "skipped" in out.stdout and not (tmp_path / "model").exists()


def test_the_router_stand_in_routes_between_clients_with_zenohd_arguments() -> None:
    port = free_port()
    proc = subprocess.Popen([sys.executable, str(ROOT / "tools/standin/router/zenohd.py"), "--listen",
                             f"tcp/127.0.0.1:{port}", "--rest-http-port", "8000", "--no-multicast-scouting"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        wait_listening(port)
        got: list[str] = []
        with zenoh.open(client_config([f"tcp/127.0.0.1:{port}"])) as a, \
                zenoh.open(client_config([f"tcp/127.0.0.1:{port}"])) as b:
            sub = a.declare_subscriber("standin/test", lambda s: got.append(s.payload.to_string()))
            deadline = time.monotonic() + 5
            while not got and time.monotonic() < deadline:
                b.put("standin/test", json.dumps("hello"))
                time.sleep(0.1)
            wait_for(lambda: got, 5)
            sub.undeclare()
    finally:
        proc.terminate()
        output = proc.communicate(timeout=10)[0]
    assert proc.returncode == 0
    assert "stand-in zenohd" in output and "no REST plugin, port 8000 is not served" in output
