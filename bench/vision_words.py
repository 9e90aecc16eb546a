"""False marks from printed words, on mark-free TUNING frames (`synthetic.py`) with words added.

    .venv/bin/python bench/vision_words.py [--frames 300] [--seed 555] [--set KEY=VALUE ...] [--json]

A real camera sees signs, posters, labels and boxes, printed in filled outline typefaces: their O is a
thick ring and their X a bar cross, exactly a mark's shape. The tuning generator's text is OpenCV's thin
stroke fonts, and the held-out generator's is DejaVu. This bench prints one or two words (NO, OK, OPEN,
TOXIC, BOX, ZOO, 100, ...; never a single letter, which is indistinguishable from a mark) on each of
`--frames` mark-free tuning frames, in typefaces neither generator uses: matplotlib's STIX and Computer
Modern fonts when matplotlib is importable (it comes with the `test` extra's zenoh-cli), else Pillow's
bundled font; 24 to 200 px high, on a light poster 60 % of the time, dark or any ink, half the frames
blurred. It reports the frames with a false mark, by shape, with and without the words on the same
frames (the words are the only difference). The words are drawn by `services/vision/printed.py`, which
the verifier's training can also use (`--printed`): for a verifier trained with them, this bench
measures what it was trained on.

This is a tuning tool (round vision13 chose `text_max_f` and `text_paper` on it): its words are not
held out from anything.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Annotated, Any

import cv2
import numpy as np
import typer

from services.vision.detector import MarkDetector, parse_settings
from services.vision.printed import print_words, typefaces
from services.vision.synthetic import SceneGenerator


def main(
    frames: Annotated[int, typer.Option(help="mark-free tuning frames")] = 300,
    seed: Annotated[int, typer.Option(help="tuning generator and word seed")] = 555,
    settings: Annotated[list[str], typer.Option("--set", help="a detector setting KEY=VALUE")] = [],  # noqa: B006
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    cv2.setNumThreads(1)
    try:
        detector = MarkDetector(parse_settings(settings))
    except ValueError as exc:
        raise typer.BadParameter(f"--set: {exc}") from None
    faces = typefaces()
    gen, rng = SceneGenerator(seed=seed), np.random.default_rng(seed)
    result: dict[str, Any] = {
        "frames": frames,
        "seed": seed,
        "settings": settings,
        "typefaces": [Path(f).name if f else "Pillow's bundled font" for f in faces],
    }
    tallies = {"without words": Counter[str](), "with words": Counter[str]()}
    for _ in range(frames):
        frame, _ = gen.frame(None)
        for key, img in (("without words", frame), ("with words", print_words(frame, rng, faces))):
            found = detector.detect(img)
            tallies[key]["frames with a false mark"] += bool(found)
            tallies[key].update(d.shape.value for d in found)
    for key, tally in tallies.items():
        result[key] = {k: tally.get(k, 0) for k in ("frames with a false mark", "X", "O", "TRIANGLE")}
        result[key]["false-mark frame rate"] = round(tally["frames with a false mark"] / max(1, frames), 4)
    if as_json:
        print(json.dumps(result, indent=2))
        return
    print(f"{frames} mark-free tuning frames, seed {seed}, typefaces: {', '.join(result['typefaces'])}")
    for key in tallies:
        r = result[key]
        print(
            f"  {key:14s} false-mark frames {r['frames with a false mark']:4d} ({100 * r['false-mark frame rate']:.1f} %)"
            f"   X {r['X']}  O {r['O']}  TRIANGLE {r['TRIANGLE']}"
        )


if __name__ == "__main__":
    typer.run(main)
