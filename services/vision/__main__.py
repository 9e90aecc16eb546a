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
from services.vision.calibration import Calibration, Undistorter
from services.vision.debounce import Confirmation, DebounceConfig
from services.vision.detector import MarkDetector, parse_settings
from services.vision.explain import CardCheck, explained
from services.vision.service import NAME, VisionSettings, serve
from services.vision.sources import EndOfStream, SourceConfigError, SourceError, open_source

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

SourceOption = Annotated[
    str,
    typer.Option(
        "--source",
        envvar="HRI_VISION_SOURCE",
        help="camera:0, camera:/dev/video0, a video file, an image folder or glob, "
        "synthetic (nothing held up until told) or synthetic:<none|cycle|paper|schedule-file>",
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
        help="K/N for the safe mark O: published once seen in K of the last N frames, none of them with an X or triangle",
    ),
]
DangerDebounceOption = Annotated[
    str,
    typer.Option(
        "--danger-debounce",
        envvar="HRI_VISION_DANGER_DEBOUNCE",
        help="K/N for the danger marks X and TRIANGLE (1/N: act on the first frame)",
    ),
]
LoopOption = Annotated[
    bool,
    typer.Option("--loop/--no-loop", envvar="HRI_VISION_LOOP", help="replay a video file or image folder"),
]
SeedOption = Annotated[int, typer.Option("--seed", help="random seed of the synthetic scene")]
LookaheadOption = Annotated[
    bool,
    typer.Option(
        "--lookahead/--no-lookahead",
        envvar="HRI_VISION_LOOKAHEAD",
        help="on a live source, judge a newer frame's coarser levels between an older frame's steps "
        "and publish it at once if it shows an X or a triangle (lookahead.py)",
    ),
]
DetectorOption = Annotated[
    str,
    typer.Option(
        "--detector",
        envvar="HRI_VISION_DETECTOR",
        help="detector settings changed from the defaults, KEY=VALUE separated by spaces or ';' "
        "(DetectorConfig fields, e.g. 'split=' turns the finger split off)",
    ),
]


CalibrationOption = Annotated[
    Path | None,
    typer.Option(
        "--calibration",
        envvar="HRI_VISION_CALIBRATION",
        help="the camera's lens calibration (OpenCV FileStorage YAML/JSON: camera_matrix, "
        "distortion_coefficients): frames are undistorted before detection",
    ),
]


def _calibration(path: Path | None) -> Calibration | None:
    return Calibration.load(path) if path is not None else None


@app.callback(invoke_without_command=True)
def main(
    ctx: typer.Context,
    robot: RobotOption = None,
    connect: ConnectOption = None,
    source: SourceOption = "camera:0",
    fps: FpsOption = None,
    debounce: DebounceOption = "3/4",
    danger_debounce: DangerDebounceOption = "1/3",
    loop: LoopOption = False,
    seed: SeedOption = 0,
    detector: DetectorOption = "",
    calibration: CalibrationOption = None,
    lookahead: LookaheadOption = False,
) -> None:
    """Run the vision service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    # invalid configuration: one line on stderr and exit 2, before any session is opened
    try:
        window = Confirmation(
            safe=DebounceConfig.parse(debounce), danger=DebounceConfig.parse(danger_debounce)
        )
        config = parse_settings(detector)
        lens = _calibration(calibration)
        open_source(source, loop=loop, seed=seed)  # builds (does not open) the source: checks the spec
    except (ValueError, SourceConfigError) as exc:
        typer.echo(f"vision: invalid configuration: {exc}", err=True)
        raise typer.Exit(2) from None
    except SourceError:  # missing now (no camera, no file): the service reports it and retries
        pass
    settings = VisionSettings(
        source=source,
        fps=fps,
        debounce=window,
        loop=loop,
        seed=seed,
        detector=config,
        calibration=lens,
        lookahead=lookahead,
    )
    raise typer.Exit(run_service(NAME, partial(serve, settings=settings), robot=robot, connect=connect))


@app.command()
def detect(
    images: Annotated[list[Path], typer.Argument(help="image files")],
    annotate_dir: Annotated[
        Path | None, typer.Option("--annotate", help="write annotated copies here")
    ] = None,
    settings: DetectorOption = "",
    calibration: CalibrationOption = None,
    explain: Annotated[
        bool,
        typer.Option(
            "--explain",
            help="also say on stderr, for each shape the tests read as a mark but did not report, which rule "
            "refused it (services/vision/explain.py)",
        ),
    ] = False,
) -> None:
    """Print one MarkObservation JSON line per image (no debounce; `frame` is the image's position).

    An unreadable image prints an error on stderr instead of its line; the exit code is then 1.
    """
    try:
        detector = MarkDetector(parse_settings(settings))
        lens = _calibration(calibration)
    except ValueError as exc:
        typer.echo(f"vision: invalid configuration: {exc}", err=True)
        raise typer.Exit(2) from None
    undistort = Undistorter(lens) if lens is not None else None
    failed = 0
    if annotate_dir is not None:
        annotate_dir.mkdir(parents=True, exist_ok=True)
    for i, path in enumerate(images):
        image = cv2.imread(str(path), cv2.IMREAD_COLOR) if path.is_file() else None
        if image is None:
            failed += 1
            typer.echo(f"error: {path}: not a readable image", err=True)
            continue
        if undistort is not None:
            image = undistort(image)
        found, misses = explained(detector, image) if explain else (detector.detect(image), [])
        obs = MarkObservation(stamp=os.path.getmtime(path), frame=i, marks=[d.to_mark() for d in found])
        sys.stdout.write(obs.model_dump_json() + "\n")
        sys.stdout.flush()
        if annotate_dir is not None:
            out = annotate_dir / f"{path.stem}.annotated.png"
            cv2.imwrite(str(out), annotate(image, found))
        for miss in misses:
            x, y, w, h = miss.box
            typer.echo(f"{path}: {miss.shape.value} at {x},{y} {w}x{h} not reported: {miss.reason}", err=True)
    raise typer.Exit(1 if failed else 0)


@app.command()
def check(
    source: SourceOption = "camera:0",
    frames: Annotated[
        int, typer.Option("--frames", min=1, help="frames to look at (fewer if a file or folder ends first)")
    ] = 30,
    settings: DetectorOption = "",
    calibration: CalibrationOption = None,
    seed: SeedOption = 0,
) -> None:
    """Hold a card up to the camera: in how many frames each mark was reported, and which rule refused any shape
    that was read as a mark but not reported (explain.py). Ctrl-C stops early and still prints the summary."""
    try:
        detector = MarkDetector(parse_settings(settings))
        lens = _calibration(calibration)
        src = open_source(source, seed=seed)
    except (ValueError, SourceConfigError) as exc:
        typer.echo(f"vision: invalid configuration: {exc}", err=True)
        raise typer.Exit(2) from None
    except SourceError as exc:
        typer.echo(f"vision: {exc}", err=True)
        raise typer.Exit(1) from None
    undistort = Undistorter(lens) if lens is not None else None
    seen = CardCheck()
    failed = False
    try:
        src.open()
        while seen.frames < frames:
            frame = src.read(timeout=5.0)
            if frame is None:
                typer.echo(f"vision: no frame from {source} in 5 s", err=True)
                break
            image = undistort(frame.image) if undistort is not None else frame.image
            found, misses = explained(detector, image)
            seen.add([d.shape for d in found], misses)
    except EndOfStream:
        pass
    except SourceError as exc:  # no such camera, or it stopped
        typer.echo(f"vision: {exc}", err=True)
        failed = True
    except KeyboardInterrupt:
        pass
    finally:
        src.close()
    for line in seen.summary():
        typer.echo(line)
    raise typer.Exit(1 if failed else 0)


if __name__ == "__main__":
    app()
