"""Printed words in filled outline typefaces, drawn over a frame: the signs, posters, labels and boxes a
real camera sees, whose O is a thick ring and X a bar cross - exactly a mark's shape.

Used by `bench/vision_words.py` (false marks with and without the words) and by the verifier's training
(`training.py --printed`), never by the service: it needs Pillow, and matplotlib for its fonts (STIX and
Computer Modern, typefaces neither the tuning generator, OpenCV's stroke fonts, nor the held-out
generator, DejaVu, uses); without matplotlib, Pillow's bundled font.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

WORDS = (
    "NO",
    "GO",
    "OK",
    "ON",
    "ZOO",
    "BOOK",
    "FOOD",
    "LOOK",
    "STOP",
    "OPEN",
    "100",
    "2020",
    "COOL",
    "DOOR",
    "MOON",
    "O2",
    "OXO",
    "BOX",
    "XO",
    "TOXIC",
    "EXIT",
    "SALE",
    "A4",
    "VOX",
    "40%",
    "ROOM 10",
    "OO",
)
MPL_FACES = (
    "STIXGeneralBol.ttf",
    "STIXGeneral.ttf",
    "STIXGeneralBolIta.ttf",
    "cmb10.ttf",
    "cmss10.ttf",
    "cmr10.ttf",
    "cmtt10.ttf",
)
Box = tuple[int, int, int, int]  # x, y, w, h
PLACEMENTS = 10  # tries to place a word clear of the boxes to avoid before it is left out


def typefaces() -> list[str | None]:
    """Font files of matplotlib's STIX and Computer Modern faces, or [None]: Pillow's bundled font."""
    try:
        import matplotlib
    except ImportError:
        return [None]
    folder = Path(matplotlib.__file__).parent / "mpl-data" / "fonts" / "ttf"
    found: list[str | None] = [str(folder / f) for f in MPL_FACES if (folder / f).exists()]
    return found or [None]


def _clear(box: Box, avoid: Sequence[Box]) -> bool:
    """True when `box` keeps out of every box of `avoid` grown by half its size on each side (a word
    printed right beside a mark would change what the mark is: a letter among letters)."""
    x, y, w, h = box
    for ax, ay, aw, ah in avoid:
        if x < ax + 1.5 * aw and ax - 0.5 * aw < x + w and y < ay + 1.5 * ah and ay - 0.5 * ah < y + h:
            return False
    return True


def print_words(
    frame: np.ndarray,
    rng: np.random.Generator,
    faces: list[str | None],
    avoid: Sequence[Box] = (),
    blur: bool = True,
) -> np.ndarray:
    """`frame` (BGR) with one or two words printed on it, 24 to 200 px high, on a light poster 60 % of
    the time, in dark (70 %) or any ink, the whole frame blurred half the time (with `blur`: words put
    on a finished frame; without, on a scene's background, which the camera effects then blur); no word
    near a box of `avoid`."""
    img = Image.fromarray(np.ascontiguousarray(frame[:, :, ::-1]))
    draw = ImageDraw.Draw(img)
    for _ in range(int(rng.integers(1, 3))):
        word = WORDS[int(rng.integers(len(WORDS)))]
        size = int(np.exp(rng.uniform(np.log(24), np.log(200))))
        face = faces[int(rng.integers(len(faces)))]
        font = ImageFont.truetype(face, size) if face else ImageFont.load_default(size=size)
        x0, y0, x1, y1 = draw.textbbox((0, 0), word, font=font)
        pad = int(0.3 * (y1 - y0))
        for _try in range(PLACEMENTS):
            px = int(rng.integers(0, max(1, img.width - (x1 - x0))))
            py = int(rng.integers(0, max(1, img.height - (y1 - y0))))
            if _clear((px + x0 - pad, py + y0 - pad, x1 - x0 + 2 * pad, y1 - y0 + 2 * pad), avoid):
                break
        else:
            continue
        if rng.random() < 0.6:  # a poster or label behind the word
            grey = int(rng.integers(190, 250))
            draw.rectangle(
                (px + x0 - pad, py + y0 - pad, px + x1 + pad, py + y1 + pad), fill=(grey, grey, grey - 5)
            )
        dark = rng.random() < 0.7
        ink = tuple(int(v) for v in rng.integers(0, 90 if dark else 256, 3))
        draw.text((px, py), word, font=font, fill=ink)
    out = np.asarray(img)[:, :, ::-1].copy()
    if blur and rng.random() < 0.5:
        k = int(rng.integers(1, 4)) * 2 + 1
        out = cv2.GaussianBlur(out, (k, k), 0)
    return out
