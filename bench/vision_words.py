"""False marks from printed words, on mark-free TUNING frames (`synthetic.py`) with words added.

    .venv/bin/python bench/vision_words.py [--frames 300] [--seed 555] [--set KEY=VALUE ...] [--json]

A real camera sees signs, posters, labels and boxes, printed in filled outline typefaces: their O is a
thick ring and their X a bar cross, exactly a mark's shape. The tuning generator's text is OpenCV's thin
stroke fonts, and the held-out generator's is DejaVu. This bench prints one or two words (NO, OK, OPEN,
TOXIC, BOX, ZOO, 100, ...; never a single letter, which is indistinguishable from a mark) on each of
`--frames` mark-free tuning frames, in typefaces neither generator uses: matplotlib's STIX and Computer
Modern fonts when matplotlib is importable (it comes with the `dev` extra's zenoh-cli), else Pillow's
bundled font; 24 to 200 px high, on a light poster 60 % of the time, dark or any ink, half the frames
blurred. It reports the frames with a false mark, by shape, with and without the words on the same
frames (the words are the only difference).

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
from PIL import Image, ImageDraw, ImageFont

from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator

WORDS = ("NO", "GO", "OK", "ON", "ZOO", "BOOK", "FOOD", "LOOK", "STOP", "OPEN", "100", "2020", "COOL",
         "DOOR", "MOON", "O2", "OXO", "BOX", "XO", "TOXIC", "EXIT", "SALE", "A4", "VOX", "40%", "ROOM 10", "OO")
MPL_FACES = ("STIXGeneralBol.ttf", "STIXGeneral.ttf", "STIXGeneralBolIta.ttf", "cmb10.ttf", "cmss10.ttf",
             "cmr10.ttf", "cmtt10.ttf")


def typefaces() -> list[str | None]:
    """Font files of matplotlib's STIX and Computer Modern faces, or [None]: Pillow's bundled font."""
    try:
        import matplotlib
    except ImportError:
        return [None]
    folder = Path(matplotlib.__file__).parent / "mpl-data" / "fonts" / "ttf"
    found: list[str | None] = [str(folder / f) for f in MPL_FACES if (folder / f).exists()]
    return found or [None]


def print_words(frame: np.ndarray, rng: np.random.Generator, faces: list[str | None]) -> np.ndarray:
    img = Image.fromarray(np.ascontiguousarray(frame[:, :, ::-1]))
    draw = ImageDraw.Draw(img)
    for _ in range(int(rng.integers(1, 3))):
        word = WORDS[int(rng.integers(len(WORDS)))]
        size = int(np.exp(rng.uniform(np.log(24), np.log(200))))
        face = faces[int(rng.integers(len(faces)))]
        font = ImageFont.truetype(face, size) if face else ImageFont.load_default(size=size)
        x0, y0, x1, y1 = draw.textbbox((0, 0), word, font=font)
        px = int(rng.integers(0, max(1, img.width - (x1 - x0))))
        py = int(rng.integers(0, max(1, img.height - (y1 - y0))))
        if rng.random() < 0.6:  # a poster or label behind the word
            pad, grey = int(0.3 * (y1 - y0)), int(rng.integers(190, 250))
            draw.rectangle((px + x0 - pad, py + y0 - pad, px + x1 + pad, py + y1 + pad), fill=(grey, grey, grey - 5))
        dark = rng.random() < 0.7
        ink = tuple(int(v) for v in rng.integers(0, 90 if dark else 256, 3))
        draw.text((px, py), word, font=font, fill=ink)
    out = np.asarray(img)[:, :, ::-1].copy()
    if rng.random() < 0.5:
        k = int(rng.integers(1, 4)) * 2 + 1
        out = cv2.GaussianBlur(out, (k, k), 0)
    return out


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
    result: dict[str, Any] = {"frames": frames, "seed": seed, "settings": settings,
                              "typefaces": [Path(f).name if f else "Pillow's bundled font" for f in faces]}
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
        print(f"  {key:14s} false-mark frames {r['frames with a false mark']:4d} ({100 * r['false-mark frame rate']:.1f} %)"
              f"   X {r['X']}  O {r['O']}  TRIANGLE {r['TRIANGLE']}")


if __name__ == "__main__":
    typer.run(main)
