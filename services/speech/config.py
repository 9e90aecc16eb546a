"""Speech service settings: voice, rate, volume, output, queue bound and staleness cap.

Each setting has an environment variable (DESIGN.md, Configuration) and a command-line option;
the option wins. Values are checked here so a bad one is a clear error at start, never a crash later.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from services.runtime import ConfigError, default_state_dir

DEFAULT_VOICE = "en-us"
"""espeak-ng's American English voice: pocketsphinx's US model recognises it best (round-trip test)."""
DEFAULT_RATE = 175
"""Words per minute, espeak-ng's own default; the round-trip test decodes the refusal word for word at it."""
DEFAULT_VOLUME = 100
"""espeak-ng amplitude, 0..200."""
DEFAULT_QUEUE_SIZE = 4
DEFAULT_MAX_AGE_S = 5.0
DEFAULT_MAX_CHARS = 400

RATE_RANGE = (80, 450)
"""espeak-ng clamps below 80 wpm and garbles far above 450."""
VOLUME_RANGE = (0, 200)

DEVICE = "device"
"""`HRI_SPEECH_OUT=device` plays on the default sound device; `device:<alsa-pcm>` picks one."""


@dataclass(frozen=True)
class OutputTarget:
    """Where audio goes: a sound device (optionally a named ALSA PCM) or a folder of `<id>.wav` files."""

    folder: Path | None = None
    device: str | None = None  # "" for the default device, else an ALSA PCM name such as "plughw:1"

    @property
    def is_device(self) -> bool:
        return self.device is not None

    def describe(self) -> str:
        if self.device is not None:
            return f"device:{self.device}" if self.device else "device"
        return f"folder:{self.folder}"


@dataclass(frozen=True)
class SpeechConfig:
    voice: str = DEFAULT_VOICE
    rate: int = DEFAULT_RATE
    volume: int = DEFAULT_VOLUME
    out: OutputTarget | None = None
    """None: the default folder of the robot the service runs for (`default_folder`)."""
    queue_size: int = DEFAULT_QUEUE_SIZE
    max_age_s: float = DEFAULT_MAX_AGE_S
    max_chars: int = DEFAULT_MAX_CHARS

    def __post_init__(self) -> None:
        if not self.voice.strip() or any(c.isspace() for c in self.voice):
            raise ConfigError(
                f"voice {self.voice!r}: give one espeak-ng voice name (see `espeak-ng --voices`)"
            )
        _check_range("rate", self.rate, RATE_RANGE, "words per minute")
        _check_range("volume", self.volume, VOLUME_RANGE, "espeak-ng amplitude")
        if self.queue_size < 1:
            raise ConfigError(f"queue size {self.queue_size}: must be at least 1")
        if not self.max_age_s > 0:
            raise ConfigError(f"max age {self.max_age_s} s: must be a positive number of seconds")
        if self.max_chars < 1:
            raise ConfigError(f"max chars {self.max_chars}: must be at least 1")

    def output_for(self, robot: str) -> OutputTarget:
        return self.out if self.out is not None else OutputTarget(folder=default_folder(robot))


def _check_range(name: str, value: int, bounds: tuple[int, int], unit: str) -> None:
    lo, hi = bounds
    if not lo <= value <= hi:
        raise ConfigError(f"{name} {value}: must be {lo}..{hi} ({unit})")


def default_folder(robot: str) -> Path:
    """`<state dir>/speech`: `$HRI_STATE_DIR/speech`, else `$XDG_STATE_HOME/hri/<robot>/speech`
    (XDG_STATE_HOME defaulting to ~/.local/state), like every service's state."""
    return default_state_dir(robot) / "speech"


def parse_output(raw: str | None) -> OutputTarget | None:
    """`device`, `device:<pcm>`, a folder path, or unset/empty (None) for the default folder."""
    raw = (raw or "").strip()
    if not raw:
        return None
    if raw == DEVICE:
        return OutputTarget(device="")
    if raw.startswith(DEVICE + ":"):
        pcm = raw[len(DEVICE) + 1 :].strip()
        if not pcm:
            raise ConfigError(
                "HRI_SPEECH_OUT=device: needs an ALSA PCM name after the colon, e.g. device:plughw:1"
            )
        return OutputTarget(device=pcm)
    folder = Path(raw).expanduser()
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"speech output {folder} exists and is not a folder; give a folder or `device`")
    return OutputTarget(folder=folder)
