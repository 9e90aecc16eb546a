"""Where synthesised speech goes: a folder of `<id>.wav` files, or the sound device via `aplay`.

Both outputs make "speaking" last as long as the audio: the device because playing takes that
long, the folder because it waits the WAV's duration after writing it, so that the reasoner and
the demo see the timing a real robot would have. Either wait ends early when `stop` is set.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import threading
import wave
from pathlib import Path
from typing import Protocol

from services.speech.tts import Synthesis

APLAY_HINT = "install `aplay` with `sudo apt-get install alsa-utils`"
FOLDER_HINT = "or write WAV files instead (HRI_SPEECH_OUT=<folder>, or `say --out FILE.wav`)"

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


class PlaybackError(RuntimeError):
    """The output could not take the audio (no sound device, unwritable folder)."""


def file_stem(utterance_id: str) -> str:
    """A request id as a safe file name: no path separators, no leading dot, at most 120 characters."""
    stem = _UNSAFE.sub("_", utterance_id)[:120]
    return "_" + stem[1:] if stem.startswith(".") else stem


class Output(Protocol):
    def describe(self) -> str: ...

    def path_for(self, utterance_id: str) -> Path:
        """Where the synthesiser should write this utterance's WAV."""
        ...

    def probe(self) -> str | None:
        """None when the output works now, else what is wrong (for health and logs)."""
        ...

    def play(self, audio: Synthesis, stop: threading.Event) -> bool:
        """Deliver `audio`, returning when it has been heard: True, or False if `stop` cut it short."""
        ...

    def close(self) -> None: ...


class FolderOutput:
    """Writes `<folder>/<id>.wav` and waits out the audio's duration."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder

    def describe(self) -> str:
        return f"folder:{self.folder}"

    def path_for(self, utterance_id: str) -> Path:
        return self.folder / f"{file_stem(utterance_id)}.wav"

    def probe(self) -> str | None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile(dir=self.folder, prefix=".probe-"):
                pass
        except OSError as exc:
            return f"cannot write to {self.folder}: {exc.strerror or exc}"
        return None

    def adopt(self, audio: Synthesis, utterance_id: str) -> Synthesis:
        """Move audio made elsewhere (for a failed device) into this folder."""
        dest = self.path_for(utterance_id)
        self.folder.mkdir(parents=True, exist_ok=True)
        shutil.move(str(audio.path), dest)
        return Synthesis(path=dest, duration_s=audio.duration_s, synth_s=audio.synth_s)

    def play(self, audio: Synthesis, stop: threading.Event) -> bool:
        return not stop.wait(audio.duration_s)

    def close(self) -> None:
        pass


class AplayOutput:
    """Plays each WAV with ALSA's `aplay` on the default or a named PCM device."""

    def __init__(self, pcm: str = "", *, binary: str = "aplay") -> None:
        self.pcm = pcm
        self.binary = binary
        self._tmp = Path(tempfile.mkdtemp(prefix="hri-speech-"))

    def describe(self) -> str:
        return f"device:{self.pcm}" if self.pcm else "device"

    def path_for(self, utterance_id: str) -> Path:
        return self._tmp / f"{file_stem(utterance_id)}.wav"

    def _command(self, path: Path) -> list[str]:
        program = shutil.which(self.binary)
        if program is None:
            raise PlaybackError(
                f"cannot play on {self.describe()}: `{self.binary}` not found; {APLAY_HINT}, {FOLDER_HINT}"
            )
        return [program, "-q", *(["-D", self.pcm] if self.pcm else []), str(path)]

    def probe(self) -> str | None:
        """Open the device for 10 ms of silence: the only sure test that it exists and is free."""
        path = self._tmp / ".probe.wav"
        with wave.open(str(path), "wb") as w:
            w.setnchannels(1)
            w.setsampwidth(2)
            w.setframerate(22050)
            w.writeframes(b"\0\0" * 220)
        try:
            self._run(path, threading.Event())
        except PlaybackError as exc:
            return str(exc)
        return None

    def play(self, audio: Synthesis, stop: threading.Event) -> bool:
        """Played files are removed; on PlaybackError the file stays for the caller to keep elsewhere."""
        finished = self._run(audio.path, stop)
        audio.path.unlink(missing_ok=True)
        return finished

    def _run(self, path: Path, stop: threading.Event) -> bool:
        try:
            proc = subprocess.Popen(
                self._command(path),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
            )
        except OSError as exc:
            raise PlaybackError(f"cannot run {self.binary}: {exc}") from None
        while proc.poll() is None:
            if stop.wait(0.02):
                proc.terminate()
                proc.wait(2)
                return False
        err = proc.stderr.read().decode("utf-8", "replace").strip() if proc.stderr else ""
        if proc.stderr:
            proc.stderr.close()
        if proc.returncode != 0:
            last = err.splitlines()[-1] if err else f"exit code {proc.returncode}"
            raise PlaybackError(f"sound output {self.describe()} unusable: {last}; {FOLDER_HINT}")
        return True

    def close(self) -> None:
        shutil.rmtree(self._tmp, ignore_errors=True)

