"""`python -m services.vision`: run the vision service; `... detect IMAGE...` runs the detector on images."""

from __future__ import annotations

import os
import sys
from functools import partial
from pathlib import Path
from typing import Annotated

import cv2
import typer

from schemas.messages import MarkObservation
from services.runtime import run_service
from services.runtime.cli import ConnectOption, RobotOption
from services.vision.annotate import annotate
from services.vision.debounce import DebounceConfig
from services.vision.detector import MarkDetector
from services.vision.service import NAME, VisionSettings, serve

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

SourceOption = Annotated[
    str,
    typer.Option(
        "--source",
        envvar="HRI_VISION_SOURCE",
        help="camera:0, camera:/dev/video0, a video file, an image folder or glob, "
        "synthetic:<none|cycle|paper|schedule-file>",
    ),
]
FpsOption = Annotated[
    float | None,
    typer.Option(
        "--fps",
        envvar="HRI_VISION_FPS",
        min=0.1,
        help="frame-rate cap [default: camera rate; 15 for synthetic and folders; a video's own rate]",
    ),
]
DebounceOption = Annotated[
    str,
    typer.Option(
        "--debounce",
        envvar="HRI_VISION_DEBOUNCE",
        help="K/N: a mark is published once seen in K of the last N frames",
    ),
]
LoopOption = Annotated[
    bool,
    typer.Option("--loop/--no-loop", envvar="HRI_VISION_LOOP", help="replay a video file or image folder"),
]
SeedOption = Annotated[int, typer.Option("--seed", help="random seed of the synthetic scene")]


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    robot: RobotOption = None,
    connect: ConnectOption = None,
    source: SourceOption = "camera:0",
    fps: FpsOption = None,
    debounce: DebounceOption = "3/5",
    loop: LoopOption = False,
    seed: SeedOption = 0,
) -> None:
    """Run the vision service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    try:
        window = DebounceConfig.parse(debounce)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--debounce") from None
    settings = VisionSettings(source=source, fps=fps, debounce=window, loop=loop, seed=seed)
    raise typer.Exit(run_service(NAME, partial(serve, settings=settings), robot=robot, connect=connect))


@app.command()
def detect(
    images: Annotated[list[Path], typer.Argument(help="image files")],
    annotate_dir: Annotated[
        Path | None, typer.Option("--annotate", help="write annotated copies here")
    ] = None,
) -> None:
    """Print one MarkObservation JSON line per image (no debounce; `frame` is the image's position).

    An unreadable image prints an error on stderr instead of its line; the exit code is then 1.
    """
    detector = MarkDetector()
    failed = 0
    if annotate_dir is not None:
        annotate_dir.mkdir(parents=True, exist_ok=True)
    for i, path in enumerate(images):
        image = cv2.imread(str(path), cv2.IMREAD_COLOR) if path.is_file() else None
        if image is None:
            failed += 1
            typer.echo(f"error: {path}: not a readable image", err=True)
            continue
        found = detector.detect(image)
        obs = MarkObservation(stamp=os.path.getmtime(path), frame=i, marks=[d.to_mark() for d in found])
        sys.stdout.write(obs.model_dump_json() + "\n")
        sys.stdout.flush()
        if annotate_dir is not None:
            out = annotate_dir / f"{path.stem}.annotated.png"
            cv2.imwrite(str(out), annotate(image, found))
    raise typer.Exit(1 if failed else 0)


if __name__ == "__main__":
    app()
