"""What card the robot can see: one mark on one plain card, the card's border and the background varied.

    .venv/bin/python bench/vision_cards.py [--ink black|blue|red|green] [--set KEY=VALUE ...] [--json]

Neither frame generator answers a user's first question, "how do I make a card?", because each draws cards of its
own proportions. This bench draws, for every mark (X, O, an outline TRIANGLE, a filled TRIANGLE), one card in the
middle of a 640x480 frame: black ink (grey 30; `--ink` blue, red or green) on white paper (230), strokes an eighth of
the mark, the mark 40, 80 or 160 px wide, turned by 0, 25 or 60 degrees, with a card border on each side of 0.1 to 3
times the mark's width (at 3 an A4 sheet round a 4 cm mark; past the frame's edge, a sheet held close fills the view)
in front of a background of mid grey (120), dark grey (60), a blurred texture, or white as bright as the card (a
white card held against a white wall or shirt: no card edge to see). Light sensor noise (sigma 2) and a one-pixel
blur; nothing else. It prints, per mark, the share of its 9 frames (3 sizes x 3 turns) in which the detector found
that mark (box IoU >= 0.5) and the false marks found, by background and border.

It is a probe of the detector's definition of a card, not a measure of recall: `bench/vision_bench.py` is that.
By the contract a filled triangle that is not on a card is clutter; the detector's card is a light surface that
ends within about the mark's width (the verifier's context crop is 4 x the mark: `verifier.CONTEXT`), so a filled
triangle with more paper round it than that, or on a card no darker than what is behind it, is taken for a
triangle painted on a wall (vision README, "What counts as a mark").
"""

from __future__ import annotations

import json
from typing import Annotated, Any

import cv2
import numpy as np
import typer

from schemas.messages import Shape
from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import _draw_mark
from services.vision.training import iou

W, H = 640, 480
PAPER = 230
INKS: dict[str, tuple[int, int, int]] = {  # BGR, as a marker pen's on white paper
    "black": (30, 30, 30),
    "blue": (150, 60, 20),
    "red": (40, 40, 200),
    "green": (60, 140, 30),
}
MARKS: dict[str, tuple[Shape, bool]] = {
    "X": (Shape.X, False),
    "O": (Shape.O, False),
    "TRIANGLE": (Shape.TRIANGLE, False),
    "filled TRIANGLE": (Shape.TRIANGLE, True),
}
BORDERS = (0.1, 0.3, 0.6, 1.0, 1.5, 3.0)  # paper on each side of the mark, multiples of its width
BACKGROUNDS = ("grey", "dark", "texture", "white")
SIZES = (40, 80, 160)
TURNS = (0.0, 25.0, 60.0)


def background(kind: str, rng: np.random.Generator) -> np.ndarray:
    """The frame behind the card (BGR)."""
    if kind == "texture":
        noise = rng.integers(30, 210, (H // 4, W // 4), dtype=np.uint8)
        grey = cv2.GaussianBlur(cv2.resize(noise, (W, H), interpolation=cv2.INTER_LINEAR), (0, 0), 2)
    else:
        level = {"grey": 120, "dark": 60, "white": PAPER}[kind]
        grey = np.full((H, W), level, np.uint8)
    return cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)


def card_frame(
    kind: str,
    shape: Shape,
    filled: bool,
    size: int,
    border: float,
    turn: float,
    rng: np.random.Generator,
    ink: tuple[int, int, int] = INKS["black"],
) -> tuple[np.ndarray, tuple[int, int, int, int]]:
    """One frame: the card (turned by `turn` degrees about the frame's centre) over the background, and the
    mark's box."""
    side = int(round(size * (1 + 2 * border)))
    card = np.full((side, side, 3), PAPER, np.uint8)
    pts = _draw_mark(card, shape, (side / 2, side / 2), float(size), size / 8, ink, 0.0, filled)
    # the card's centre on the frame's centre, turned
    m = cv2.getRotationMatrix2D((side / 2, side / 2), turn, 1.0)
    m[:, 2] += (W / 2 - side / 2, H / 2 - side / 2)
    img = background(kind, rng)
    warped = cv2.warpAffine(card, m, (W, H), flags=cv2.INTER_LINEAR)
    mask = cv2.warpAffine(np.full((side, side), 255, np.uint8), m, (W, H), flags=cv2.INTER_LINEAR)
    img = np.where(mask[..., None] > 127, warped, img)
    moved = cv2.transform(pts.reshape(-1, 1, 2).astype(np.float32), m).reshape(-1, 2)
    x0, y0 = np.floor(moved.min(axis=0)).astype(int)
    x1, y1 = np.ceil(moved.max(axis=0)).astype(int)
    img = cv2.GaussianBlur(img, (3, 3), 0)
    noisy = img.astype(np.float32) + rng.normal(0.0, 2.0, img.shape).astype(np.float32)
    return np.clip(noisy, 0, 255).astype(np.uint8), (int(x0), int(y0), int(x1 - x0), int(y1 - y0))


def probe(
    detector: MarkDetector,
    seed: int = 0,
    marks: tuple[str, ...] = tuple(MARKS),
    borders: tuple[float, ...] = BORDERS,
    sizes: tuple[int, ...] = SIZES,
    turns: tuple[float, ...] = TURNS,
    ink: str = "black",
) -> dict[str, Any]:
    """Found share and false marks per mark, background and border."""
    rng = np.random.default_rng(seed)
    out: dict[str, Any] = {}
    for name in marks:
        shape, filled = MARKS[name]
        table: dict[str, dict[str, Any]] = {}
        for kind in BACKGROUNDS:
            row: dict[str, Any] = {}
            for border in borders:
                found = false = 0
                for size in sizes:
                    for turn in turns:
                        img, box = card_frame(kind, shape, filled, size, border, turn, rng, INKS[ink])
                        hit = False
                        for d in detector.detect(img):
                            if not hit and d.shape is shape and iou(d.box, box) >= 0.5:
                                hit = True
                            else:
                                false += 1
                        found += hit
                row[str(border)] = {"found": round(found / (len(sizes) * len(turns)), 3), "false": false}
            table[kind] = row
        out[name] = table
    return out


def main(
    settings: Annotated[list[str], typer.Option("--set", help="a detector setting KEY=VALUE")] = [],  # noqa: B006
    seed: Annotated[int, typer.Option(help="the noise and texture seed")] = 0,
    ink: Annotated[str, typer.Option(help=f"the ink: {', '.join(INKS)}")] = "black",
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
) -> None:
    cv2.setNumThreads(1)
    if ink not in INKS:
        raise typer.BadParameter(f"{ink!r}: one of {', '.join(INKS)}", param_hint="--ink")
    try:
        config = parse_settings(settings)
    except ValueError as exc:
        raise typer.BadParameter(f"--set: {exc}") from None
    result = probe(MarkDetector(config), seed, ink=ink)
    if as_json:
        typer.echo(json.dumps({"settings": settings, "seed": seed, "ink": ink, "marks": result}, indent=2))
        return
    lines = [
        f"one card mid-frame, {ink} ink {INKS[ink]} (BGR) on paper {PAPER}; share of {len(SIZES) * len(TURNS)} frames "
        f"(marks {', '.join(map(str, SIZES))} px, turned {', '.join(f'{t:g}' for t in TURNS)} deg) "
        "in which the mark was found [false marks]",
        f"detector settings: {' '.join(settings) if settings else 'the defaults'}",
    ]
    head = f"{'border (x mark width)':<24}" + "".join(f"{b:>10g}" for b in BORDERS)
    for name, table in result.items():
        lines += ["", name, head]
        for kind, row in table.items():
            cells = "".join(
                f"{row[str(b)]['found']:>6.2f}" + (f"[{row[str(b)]['false']}]" if row[str(b)]["false"] else "   ").rjust(4)
                for b in BORDERS
            )
            lines.append(f"  {kind + ' background':<22}{cells}")
    typer.echo("\n".join(lines))


if __name__ == "__main__":
    typer.run(main)
