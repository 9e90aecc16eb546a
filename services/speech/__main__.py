"""`python -m services.speech`: run the speech service, or `say` one line (espeak-ng)."""

from __future__ import annotations

import json
import sys
import threading
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from services.runtime import ConfigError, get_logger, run_service
from services.runtime.cli import ConnectOption, RobotOption
from services.speech.config import (
    DEFAULT_MAX_AGE_S,
    DEFAULT_MAX_CHARS,
    DEFAULT_QUEUE_SIZE,
    DEFAULT_RATE,
    DEFAULT_VOICE,
    DEFAULT_VOLUME,
    SpeechConfig,
    parse_output,
)
from services.speech.player import AplayOutput, PlaybackError
from services.speech.service import NAME, serve
from services.speech.text import TextRejected, clean_text
from services.speech.tts import EngineMissing, EspeakNg, SynthesisError, unknown_voice

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

EXIT_FAILED = 1
EXIT_NO_ENGINE = 3

VoiceOption = Annotated[
    str, typer.Option("--voice", envvar="HRI_SPEECH_VOICE", help="espeak-ng voice (`espeak-ng --voices`)")
]
RateOption = Annotated[
    int, typer.Option("--rate", envvar="HRI_SPEECH_RATE", min=80, max=450, help="Words per minute")
]
VolumeOption = Annotated[
    int,
    typer.Option("--volume", envvar="HRI_SPEECH_VOLUME", min=0, max=200, help="espeak-ng amplitude 0..200"),
]


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    robot: RobotOption = None,
    connect: ConnectOption = None,
    voice: VoiceOption = DEFAULT_VOICE,
    rate: RateOption = DEFAULT_RATE,
    volume: VolumeOption = DEFAULT_VOLUME,
    out: Annotated[
        str | None,
        typer.Option(
            "--out",
            envvar="HRI_SPEECH_OUT",
            help="`device` (or `device:<alsa-pcm>`) to play through aplay, or a folder to write <id>.wav "
            "files into [default: $XDG_STATE_HOME/hri/<robot>/speech]",
        ),
    ] = None,
    queue_size: Annotated[
        int, typer.Option("--queue-size", envvar="HRI_SPEECH_QUEUE", min=1, help="Requests that may wait")
    ] = DEFAULT_QUEUE_SIZE,
    max_age: Annotated[
        float,
        typer.Option("--max-age", envvar="HRI_SPEECH_MAX_AGE", min=0.01,
                     help="Seconds a request may wait for its turn before it is skipped"),
    ] = DEFAULT_MAX_AGE_S,
    max_chars: Annotated[
        int, typer.Option("--max-chars", envvar="HRI_SPEECH_MAX_CHARS", min=1, help="Longest text spoken")
    ] = DEFAULT_MAX_CHARS,
) -> None:
    """Run the speech service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    try:
        config = SpeechConfig(voice=voice, rate=rate, volume=volume, out=parse_output(out),
                              queue_size=queue_size, max_age_s=max_age, max_chars=max_chars)
        if problem := unknown_voice(config.voice):
            raise ConfigError(f"voice {config.voice!r}: {problem}")
    except ConfigError as exc:
        get_logger(NAME).error("configuration error", error=str(exc))
        raise typer.Exit(2) from None
    raise typer.Exit(run_service(NAME, lambda c: serve(c, config), robot=robot, connect=connect))


@app.command()
def say(
    text: Annotated[str, typer.Argument(help="What to say; `-` reads it from standard input")],
    out: Annotated[
        str,
        typer.Option("--out", "-o", help="A .wav file to write, or `device` / `device:<alsa-pcm>` to play"),
    ] = "device",
    voice: VoiceOption = DEFAULT_VOICE,
    rate: RateOption = DEFAULT_RATE,
    volume: VolumeOption = DEFAULT_VOLUME,
    max_chars: Annotated[
        int, typer.Option("--max-chars", min=1, help="Longest text spoken")
    ] = DEFAULT_MAX_CHARS,
) -> None:
    """Say TEXT once, into a WAV file or out loud, and print a JSON summary.

    Exit codes: 0 spoken, 1 synthesis or playback failed, 2 bad arguments, 3 espeak-ng is not installed.
    """
    try:
        line = clean_text(sys.stdin.read() if text == "-" else text, max_chars)
    except TextRejected as exc:
        _fail(f"nothing said: {exc}", 2)
    if problem := unknown_voice(voice):
        _fail(f"nothing said: {problem}", 2)
    tts = EspeakNg(voice, rate, volume)
    device = out == "device" or out.startswith("device:")
    player = AplayOutput(out.partition(":")[2]) if device else None
    dest = player.path_for("say") if player else Path(out)
    if not device and dest.is_dir():
        _fail(f"--out {out} is a folder; give a file name such as {dest / 'reply.wav'}", 2)
    try:
        audio = tts.synthesize(line, dest)
        if player is not None:
            player.play(audio, threading.Event())
    except EngineMissing as exc:
        _fail(str(exc), EXIT_NO_ENGINE)
    except (SynthesisError, PlaybackError) as exc:
        _fail(str(exc), EXIT_FAILED)
    finally:
        if player is not None:
            player.close()
    typer.echo(json.dumps({
        "text": line,
        "out": out if device else str(dest),
        "duration_s": round(audio.duration_s, 3),
        "synth_ms": round(audio.synth_s * 1000, 1),
        "voice": voice,
        "rate": rate,
        "volume": volume,
    }))


def _fail(message: str, code: int) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


if __name__ == "__main__":
    app()
