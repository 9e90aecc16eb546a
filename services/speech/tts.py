"""espeak-ng text-to-speech: text in, a complete WAV file out.

The text goes to espeak-ng on standard input (never on the command line, so text that looks like
an option is still just text), and the WAV is written next to its destination and renamed into
place, so a reader never sees half a file.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from services.speech.audio import AudioError, wav_duration

ENGINE = "espeak-ng"
INSTALL_HINT = (
    "install it with `sudo apt-get install espeak-ng` (Debian/Ubuntu; `brew install espeak-ng` on macOS)"
)


class EngineMissing(RuntimeError):
    """The espeak-ng program is not installed (or not on PATH)."""


class SynthesisError(RuntimeError):
    """espeak-ng ran but made no usable audio (bad voice, empty text, timeout)."""


@dataclass(frozen=True)
class Synthesis:
    path: Path
    duration_s: float
    synth_s: float
    """Wall time espeak-ng took, start to the file being in place."""


def missing_message(binary: str = ENGINE) -> str:
    return f"text-to-speech engine `{binary}` not found on PATH; {INSTALL_HINT}"


def _listed(program: str, which: str) -> set[str]:
    """The names `-v` accepts from `espeak-ng --voices[=variant]`: language codes, voice names and
    voice files (with and without their folder), lower-cased."""
    out = subprocess.run([program, f"--voices{which}"], capture_output=True, text=True, timeout=20,
                         check=False).stdout
    names: set[str] = set()
    for line in out.splitlines()[1:]:
        cols = line.split()
        if len(cols) >= 5:
            names |= {cols[1], cols[3], cols[4], cols[4].rpartition("/")[2]}
    return {n.lower() for n in names}


def unknown_voice(voice: str, binary: str = ENGINE) -> str | None:
    """Why espeak-ng has no voice `voice` (`<voice>` or `<voice>+<variant>`), or None if it has
    one or is not installed (that is reported on its own). espeak-ng itself falls back to its
    default voice without a word when a name is wrong."""
    program = shutil.which(binary)
    if program is None:
        return None
    base, _, variant = voice.partition("+")
    if base.lower() not in _listed(program, ""):
        return f"{binary} has no voice {base!r} (list them with `{binary} --voices`)"
    if variant and variant.lower() not in _listed(program, "=variant"):
        return f"{binary} has no variant {variant!r} (list them with `{binary} --voices=variant`)"
    return None


class EspeakNg:
    """One voice setting of espeak-ng. Thread-safe: each call runs its own process."""

    def __init__(
        self, voice: str, rate: int, volume: int, *, binary: str = ENGINE, timeout_s: float = 20.0
    ) -> None:
        self.voice = voice
        self.rate = rate
        self.volume = volume
        self.binary = binary
        self.timeout_s = timeout_s

    def locate(self) -> str:
        """The program's path, or EngineMissing with the install command."""
        path = shutil.which(self.binary)
        if path is None:
            raise EngineMissing(missing_message(self.binary))
        return path

    def check(self) -> str:
        """Prove the engine and voice work by synthesising a word; returns the engine version line."""
        program = self.locate()
        try:
            version = subprocess.run(
                [program, "--version"], capture_output=True, text=True, timeout=self.timeout_s, check=False
            ).stdout.strip()
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise EngineMissing(f"`{program} --version` failed ({exc}); {INSTALL_HINT}") from None
        with tempfile.TemporaryDirectory(prefix="hri-speech-check-") as tmp:
            self.synthesize("ok", Path(tmp) / "check.wav")
        return version.splitlines()[0] if version else self.binary

    def command(self, out: Path) -> list[str]:
        return [
            self.locate(),
            "-v", self.voice,
            "-s", str(self.rate),
            "-a", str(self.volume),
            "-b", "1",  # input is UTF-8
            "-w", str(out),
            "--stdin",
        ]  # fmt: skip

    def synthesize(self, text: str, dest: Path) -> Synthesis:
        """Write `text` spoken to `dest` (a .wav). Raises EngineMissing or SynthesisError."""
        start = time.perf_counter()
        part = dest.with_name(f".{dest.name}.{os.getpid()}.part")
        try:
            dest.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SynthesisError(f"cannot create {dest.parent}: {exc.strerror or exc}") from None
        try:
            proc = subprocess.run(
                self.command(part),
                input=text.encode("utf-8"),
                capture_output=True,
                timeout=self.timeout_s,
                check=False,
            )
        except FileNotFoundError:
            raise EngineMissing(missing_message(self.binary)) from None
        except subprocess.TimeoutExpired:
            part.unlink(missing_ok=True)
            raise SynthesisError(f"{self.binary} took longer than {self.timeout_s:.0f} s") from None
        stderr = proc.stderr.decode("utf-8", "replace").strip()
        if proc.returncode != 0 or not part.exists():
            part.unlink(missing_ok=True)
            hint = " (list voices with `espeak-ng --voices`)" if "voice" in stderr.lower() else ""
            raise SynthesisError(
                f"{self.binary} exited {proc.returncode} without audio: {stderr[-300:] or 'no message'}{hint}"
            )
        try:
            duration = wav_duration(part)
        except AudioError as exc:
            part.unlink(missing_ok=True)
            raise SynthesisError(str(exc)) from None
        if duration <= 0.0:
            part.unlink(missing_ok=True)
            raise SynthesisError(f"{self.binary} made an empty recording")
        try:
            os.replace(part, dest)
        except OSError as exc:
            part.unlink(missing_ok=True)
            raise SynthesisError(f"cannot write {dest}: {exc.strerror or exc}") from None
        return Synthesis(path=dest, duration_s=duration, synth_s=time.perf_counter() - start)
