"""Where true marks are lost in the detector, on the TUNING generator (`synthetic.py`) only.

    .venv/bin/python bench/vision_stages.py [--frames 600] [--seed 99] [--verify/--no-verify] [--propose 0.3]
                                            [--hand-variety SHARE] [--hand-drawn SHARE]

For every frame that holds a mark, every sizeable component of every binarisation and pyramid level is
followed through the detector (`MarkDetector.trace`) and the mark is charged to the furthest stage that
any component matching it reached (box IoU >= 0.4 with the true box; from the shape tests on, the
claimed shape must also be the true one, else the mark counts as lost at the shape tests):

    no component   no binarised component overlaps the mark like that (merged with a finger or the
                   card edge, broken in pieces, or too faint for the threshold)
    size/fill      dropped by the vectorised pre-filter (size, aspect, fill ratio, frame edge)
    frame ink      too much ink in the thin frame around its box
    shape          the contour shape tests saw no mark, or another shape
    unnamed        a loose candidate (the shape tests claimed no shape) that the verifier found most like
                   the true shape but did not name at its stricter thresholds (most like another: "shape")
    card .. hole   the card tests, the O's clear margin, a ring's or triangle's hole
    confidence, text line, verifier (the verifier refused a shape the shape tests claimed)
    kept           found (the bench's recall can still differ: its box rule is looser)
    proposed       lost at one of the stages above, then found by the learned proposer (`proposer.py`:
                   a proposal the verifier confirmed; `--propose 0` leaves it out, as before round vision19)

Held-out frames are deliberately not offered here: this is a tuning tool.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from typing import Annotated

import cv2
import numpy as np
import typer

from schemas.messages import Shape
from services.vision.detector import STAGES, Detection, DetectorConfig, MarkDetector, Traced
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.training import IOU, iou

ORDER: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
COLUMNS: tuple[str, ...] = (*STAGES, "proposed")


def lost_at(traced: list[Traced], shape: Shape, box: tuple[int, int, int, int]) -> str:
    """The furthest stage any component matching the true mark reached."""
    best = 0
    shape_stage = STAGES.index("shape")
    for t in traced:
        if iou(t.box, box) < IOU:
            continue
        k = STAGES.index(t.stage)
        if k > shape_stage and t.shape is not shape:
            k = shape_stage  # taken for another shape
        best = max(best, k)
    return STAGES[best]


def charged(
    found: list[Detection], traced: list[Traced], shape: Shape, box: tuple[int, int, int, int]
) -> str:
    """`lost_at`, or "proposed" for a mark the components lost that a detection (a confirmed proposal:
    every component's detection is traced as kept) matches all the same."""
    stage = lost_at(traced, shape, box)
    if stage != "kept" and any(d.shape is shape and iou(d.box, box) >= IOU for d in found):
        return "proposed"
    return stage


def main(
    frames: Annotated[int, typer.Option(help="tuning frames (a quarter are mark-free and skipped)")] = 600,
    seed: Annotated[int, typer.Option(help="tuning generator seed")] = 99,
    verify: Annotated[bool, typer.Option(help="run the learned verifier")] = True,
    propose: Annotated[
        float, typer.Option(help="the proposer's peak threshold (DetectorConfig.propose; 0: off)")
    ] = DetectorConfig.propose,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
    hand_variety: Annotated[
        float, typer.Option(help="share of cards with fingers given people's variety of fingers")
    ] = 0.0,
    hand_drawn: Annotated[
        float, typer.Option(help="share of marks drawn by hand with a pen (Variation.hand_drawn)")
    ] = 0.0,
) -> None:
    cv2.setNumThreads(1)
    gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand_variety, hand_drawn=hand_drawn))
    det = MarkDetector(DetectorConfig(verify=verify, propose=propose))
    by_class: dict[str, Counter[str]] = defaultdict(Counter)
    by_slice: dict[str, Counter[str]] = defaultdict(Counter)
    for i in range(frames):
        truth = ORDER[i % len(ORDER)]
        scene = gen.scene(truth)
        img, labels = gen.render(scene)
        if not labels:
            continue
        found, traced = det.trace(img)
        stage = charged(found, traced, labels[0].shape, labels[0].box)
        by_class[labels[0].shape.value][stage] += 1
        size = max(labels[0].box[2:])
        slices = {
            "size<80": size < 80,
            "blur>=8": scene.blur[0] >= 8,
            "fingers": scene.fingers > 0,
            # people's fingers (--hand-variety): darker skin than the default's, or wider fingers
            "dark fingers": scene.fingers > 0 and sum(scene.skin) / 3 < 110,
            "wide fingers": scene.fingers > 0 and scene.finger_width > 0.3,
            "colour ink": max(scene.ink) - min(scene.ink) > 60,
            "filled triangle": scene.filled and scene.shape is Shape.TRIANGLE,
            "dim<0.7": float(np.median(scene.light)) < 0.7,
            "by hand": scene.by_hand is not None,
        }
        for name, on in slices.items():
            if on:
                by_slice[name][stage] += 1
    total: Counter[str] = Counter()
    for c in by_class.values():
        total.update(c)
    result = {
        "frames": frames,
        "seed": seed,
        "hand_variety": hand_variety,
        "hand_drawn": hand_drawn,
        "verify": verify,
        "propose": propose if verify else 0.0,
        "stages": list(COLUMNS),
        "by_class": {k: dict(v) for k, v in sorted(by_class.items())},
        "all": dict(total),
        "by_slice": {k: dict(v) for k, v in by_slice.items()},
    }
    if as_json:
        typer.echo(json.dumps(result, indent=2))
        return
    rows = [("all", total), *sorted(by_class.items()), *by_slice.items()]
    head = f"{'marks':<16}{'n':>5} " + " ".join(f"{s[:10]:>10}" for s in COLUMNS)
    proposer = f"proposer at {propose:g}" if verify and propose > 0 else "no proposer"
    lines = [
        f"tuning generator, seed {seed}, {frames} frames, verifier {'on' if verify else 'off'}, {proposer}",
        head,
    ]
    for name, c in rows:
        n = sum(c.values())
        lines.append(f"{name:<16}{n:>5} " + " ".join(f"{c[s] / n:>10.3f}" for s in COLUMNS))
    typer.echo("\n".join(lines))


if __name__ == "__main__":
    typer.run(main)
