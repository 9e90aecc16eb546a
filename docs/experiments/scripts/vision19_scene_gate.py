"""Round vision19's gate, run before any held-out frame: the synthetic source's scenes (the demo's and
the service tests' backdrop, each shape and none) through a detector variant. Every frame of a shape
must show that shape and nothing else; no frame of the bare backdrop may show a mark.

    .venv/bin/python docs/experiments/scripts/vision19_scene_gate.py [--model proposer.onnx] [--set K=V ...]
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import cv2
import typer

from schemas.messages import Shape
from services.vision.detector import MarkDetector, parse_settings
from services.vision.proposer import Proposer
from services.vision.sources import SyntheticSource


def main(
    model: Annotated[Path | None, typer.Option(help="a proposer model other than the committed one")] = None,
    settings: Annotated[list[str] | None, typer.Option("--set")] = None,
    seeds: int = 6,
    frames: int = 20,
) -> None:
    cv2.setNumThreads(1)
    det = MarkDetector(parse_settings(settings or []))
    if model is not None and det.proposer is not None:
        det.proposer = Proposer.load(model)
    bad = 0
    for seed in range(seeds):
        src = SyntheticSource("synthetic:none", seed=seed)
        src.open()
        for shape in (None, *Shape):
            src.set_shape(shape)
            wrong = 0
            for _ in range(frames):
                frame = src.read(0.1)
                assert frame is not None
                found = [d.shape for d in det.detect(frame.image)]
                wrong += found != ([shape] if shape is not None else [])
            bad += wrong
            typer.echo(f"seed {seed} {shape.value if shape else 'none':9s} wrong frames {wrong}/{frames}")
    typer.echo(f"GATE {'PASS' if bad == 0 else 'FAIL'}: {bad} wrong frames")


if __name__ == "__main__":
    typer.run(main)
