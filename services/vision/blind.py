"""A third, blind generator of camera frames of hand-held cards with an X, O or TRIANGLE mark.

What it is: a procedural renderer of 640x480 "phone/webcam photos" used as a blind test set. Each frame
is either one card carrying exactly one mark (labelled with its shape and the axis-aligned box of the
mark's ink in the final frame) or a mark-free scene full of things that share part of a mark's look.

How it differs from ordinary synthetic drawing:
- geometry is a real pinhole camera (focal length 450-800 px, mild radial distortion sometimes): the card
  is a 3D rectangle (index card, playing card, A6/A5, sticky note, business card) rotated in 3D, tilted up
  to 45 degrees, sometimes curled like a cylinder, and rendered by inverse mapping (cv2.remap) from a
  supersampled texture of the card plane that also carries the hand holding it;
- the mark is made like a real one: a felt-tip marker (varying width, ink pooling at stroke ends,
  translucent overlapping strokes, rings that overshoot or leave a small gap, bowed triangle sides with
  rounded corners, slightly curved X bars), a printed glyph or crisp vector shape, coloured tape strips
  with torn ends and a glossy sheen, or a paper sticker with a drop shadow;
- the card has paper colour and fibre noise, ruled or grid lines, creases, a small printed word in a
  corner far from the mark, margins from very narrow to wide;
- a hand (palm, 1-4 fingers, thumb with a nail, skin tones across the human range, shading across each
  finger) holds the card at an edge or corner with a soft cast shadow on the card, or the card lies on a
  table or is pinned on a wall;
- light and sensor: directional shading, glare on glossy cards, colour temperature and white-balance
  error, under/over-exposure with clipping, motion and defocus blur, a Bayer mosaic and demosaic, shot
  and read noise, a tone curve, sharpening halos and JPEG compression;
- every background is procedural (rooms, shelves of books, doors, windows, monitors, wood, brick, tiles,
  fabric, whiteboards, posters with text, clocks, plates, plants, cables, keyboards, faces, clothing).

It was written blind: without reading the repository's detector, its two other frame generators, its
proposer/verifier or any of their experiments, and without looking at what the detector does to these
frames. Ranges were chosen to be realistic, not to make the detector's job easier or harder.

What it does NOT model: true 3D scenes behind the card (the background is a flat procedural picture with
no parallax, no lens distortion and no perspective of its own), occlusion of the card by anything other
than the hand, hands with articulated 3D fingers (the hand is a flat silhouette in the card's plane),
rolling-shutter skew, chromatic aberration, vignetting, flicker, auto-focus hunting, several cards in one
frame, marks drawn on non-paper surfaces, and printed halftone patterns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from schemas.messages import Shape

Box = tuple[int, int, int, int]  # x, y, w, h in frame pixels

FONT_DIR = Path("/usr/share/fonts/truetype/dejavu")
FONTS = ("DejaVuSans.ttf", "DejaVuSans-Bold.ttf", "DejaVuSerif.ttf", "DejaVuSansMono.ttf",
         "DejaVuSansCondensed.ttf", "DejaVuSerif-Bold.ttf")
STYLES = ("marker", "printed", "tape", "sticker")
MAX_TILT_DEG = 45.0

# sRGB BGR colours
_INKS = {
    "black": (28, 28, 30), "blue": (165, 70, 25), "navy": (105, 40, 25), "red": (40, 35, 200),
    "dark_red": (40, 30, 140), "green": (60, 140, 35), "dark_green": (45, 85, 25), "brown": (30, 60, 105),
    "purple": (125, 40, 105), "magenta": (140, 35, 190), "orange": (25, 105, 230), "teal": (115, 105, 20),
}
_PAPERS = ((246, 246, 246), (250, 250, 252), (214, 234, 246), (226, 240, 250), (185, 238, 250),
           (246, 228, 212), (226, 222, 250), (214, 244, 222), (228, 228, 228), (238, 238, 240))
_SKINS = ((200, 220, 250), (160, 190, 235), (120, 165, 225), (90, 135, 195), (60, 100, 160),
          (45, 75, 120), (35, 55, 90))
_WORDS_OX = ("BOX", "OXO", "TOXIC", "XEROX", "EXIT", "OXFORD", "FOX", "TEXT", "MAX", "ROOM 204", "NO ENTRY",
             "OFFICE", "TOKYO", "COOL", "Box 12", "oxygen", "exotic", "taxi", "zoom", "Monday", "TODO",
             "meeting 10:00", "BOOK", "LOOK", "XOXO", "index", "Fax", "Coffee")
_WORDS_SAFE = ("HI", "STEP", "LEFT", "RUN", "HERE", "PEN", "MUG", "TEST", "BLUE", "KIT", "SIT", "THE END",
               "Hi!", "REST", "HELP", "STUDY", "LUNCH", "BIKE")
_CORNER_WORDS = ("ACME", "Lab 3", "No. 47", "PROPERTY OF", "TEAM B", "v2", "Kit 5", "HRI", "#12", "DEMO")


# ----------------------------------------------------------------------------------------------- labels
@dataclass(frozen=True)
class BlindLabel:
    shape: Shape
    box: Box
    size: float  # the mark's longest side in the frame, px (max of box w, h)
    tilt_deg: float  # out-of-plane tilt of the card
    blur_px: float  # motion blur length in px (0 if none)
    finger_near: bool  # a finger/thumb within a quarter of the mark's size of the mark's ink
    filled: bool  # a filled triangle
    style: str  # how the mark was made: "marker", "printed", "tape", "sticker"


# ------------------------------------------------------------------------------------- internal records
@dataclass
class _Layer:
    """One piece of a mark in patch pixels: a coverage mask and how it changes the card."""

    mask: np.ndarray  # float32 (P, P) in [0, 1]
    colour: np.ndarray  # linear BGR (3,)
    opacity: float
    mode: str  # "sub" (translucent ink), "cover" (opaque material), "shadow", "gloss"
    is_ink: bool = True


@dataclass
class _Pose:
    ex: np.ndarray
    ey: np.ndarray
    n: np.ndarray
    origin: np.ndarray  # card centre, camera coordinates, mm
    curl: float  # 1 / radius of the cylindrical bend, 1/mm (0 = flat)
    curl_axis: int  # 0: the bend varies along u, 1: along v


@dataclass
class _Camera:
    f: float
    cx: float
    cy: float
    k1: float


@dataclass
class _Canvas:
    """The card's plane as a texture: the card, its mark and the hand; mm <-> px via k and margin."""

    k: float
    margin: float
    card_w: float
    card_h: float
    rgba: np.ndarray  # (H, W, 4) float32: linear colour and coverage
    masks: np.ndarray  # (H, W, 3) float32: the mark's ink, the visible hand, the card
    ratio: float = 1.35  # texture pixels per frame pixel at the card's nearest point

    @property
    def colour(self) -> np.ndarray:
        return self.rgba[..., :3]

    @property
    def alpha(self) -> np.ndarray:
        return self.rgba[..., 3]

    @property
    def ink(self) -> np.ndarray:
        return self.masks[..., 0]

    @property
    def hand(self) -> np.ndarray:
        return self.masks[..., 1]

    @property
    def card(self) -> np.ndarray:
        return self.masks[..., 2]

    def px(self, u: float, v: float) -> tuple[float, float]:
        return (u + self.card_w / 2 + self.margin) * self.k, (v + self.card_h / 2 + self.margin) * self.k


@dataclass
class _Plan:
    shape: Shape | None
    style: str
    filled: bool
    setting: str  # "hand", "table", "wall", "none"
    card_w: float
    card_h: float
    nonmark: str = ""
    extras: dict[str, float] = field(default_factory=dict)


# ------------------------------------------------------------------------------------------ small utils
_LIN_LUT = ((np.arange(256, dtype=np.float32) / 255.0) ** 2.2).astype(np.float32)


def _to_linear(img_u8: np.ndarray) -> np.ndarray:
    return cv2.LUT(img_u8, _LIN_LUT)


def _lin(colour: tuple[int, int, int] | np.ndarray) -> np.ndarray:
    return (np.asarray(colour, np.float32) / 255.0) ** 2.2


def _jitter(rng: np.random.Generator, colour: tuple[int, int, int], amount: float) -> tuple[int, int, int]:
    c = np.clip(np.asarray(colour, float) + rng.normal(0, amount, 3), 0, 255)
    return int(c[0]), int(c[1]), int(c[2])


def _rand_colour(rng: np.random.Generator, lo: int = 0, hi: int = 255) -> tuple[int, int, int]:
    c = rng.integers(lo, hi + 1, 3)
    return int(c[0]), int(c[1]), int(c[2])


def _rot2(a: float) -> np.ndarray:
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


@lru_cache(maxsize=128)
def _font(name: str, px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    try:
        return ImageFont.truetype(str(FONT_DIR / name), px)
    except OSError:
        try:
            return ImageFont.load_default(size=px)
        except TypeError:  # very old Pillow
            return ImageFont.load_default()


def _font_available() -> bool:
    return (FONT_DIR / "DejaVuSans.ttf").exists()


def missing_fonts() -> list[str]:
    """The font files of `FONTS` this machine lacks: their text falls back to Pillow's bundled font and a missing
    DejaVu Sans takes the glyph marks away, so the frames differ from the READMEs' for the same seed."""
    return [str(FONT_DIR / name) for name in FONTS if not (FONT_DIR / name).is_file()]


def _text_mask(text: str, name: str, px: int) -> np.ndarray:
    font = _font(name, max(6, px))
    left, top, right, bottom = font.getbbox(text)
    im = Image.new("L", (max(1, right - left + 2), max(1, bottom - top + 2)), 0)
    ImageDraw.Draw(im).text((1 - left, 1 - top), text, font=font, fill=255)
    return np.asarray(im)


@lru_cache(maxsize=8)
def _glyph(char: str) -> np.ndarray | None:
    """A glyph's ink as float32 mask cropped to its box, or None when DejaVu is missing."""
    if not _font_available():
        return None
    m = _text_mask(char, "DejaVuSans.ttf", 256).astype(np.float32) / 255.0
    ys, xs = np.nonzero(m > 0.5)
    if len(xs) == 0:
        return None
    return np.ascontiguousarray(m[ys.min():ys.max() + 1, xs.min():xs.max() + 1])


def _put_mask(img: np.ndarray, mask_u8: np.ndarray, x: int, y: int, colour: tuple[int, int, int],
              opacity: float = 1.0) -> None:
    """Alpha-blend a uint8 coverage mask of one colour into a uint8 BGR image at (x, y), clipped."""
    h, w = img.shape[:2]
    mh, mw = mask_u8.shape
    x0, y0, x1, y1 = max(0, x), max(0, y), min(w, x + mw), min(h, y + mh)
    if x0 >= x1 or y0 >= y1:
        return
    a = mask_u8[y0 - y:y1 - y, x0 - x:x1 - x].astype(np.float32)[..., None] * (opacity / 255.0)
    roi = img[y0:y1, x0:x1].astype(np.float32)
    img[y0:y1, x0:x1] = (roi * (1 - a) + np.asarray(colour, np.float32) * a).astype(np.uint8)


def _put_text(img: np.ndarray, rng: np.random.Generator, text: str, x: int, y: int, px: int,
              colour: tuple[int, int, int]) -> None:
    name = FONTS[int(rng.integers(len(FONTS)))]
    _put_mask(img, _text_mask(text, name, px), x, y, colour)


def _noise_crop(tile: np.ndarray, rng: np.random.Generator, h: int, w: int, scale: float = 1.0) -> np.ndarray:
    """A (h, w) window of a tileable noise tile, optionally magnified by `scale`."""
    t = tile
    if scale != 1.0:
        s = max(8, int(tile.shape[0] * scale))
        t = cv2.resize(tile, (s, s), interpolation=cv2.INTER_LINEAR)
    ny, nx = h // t.shape[0] + 2, w // t.shape[1] + 2
    big = cv2.repeat(t, ny, nx)
    oy, ox = int(rng.integers(t.shape[0])), int(rng.integers(t.shape[1]))
    return big[oy:oy + h, ox:ox + w]


def _soft(img: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian blur; large sigmas are done at a reduced resolution (same look, a fraction of the cost)."""
    if sigma < 3:
        return cv2.GaussianBlur(img, (0, 0), max(sigma, 0.3))
    f = sigma / 1.5
    h, w = img.shape[:2]
    sw, sh = max(1, int(w / f)), max(1, int(h / f))
    small = cv2.resize(img, (sw, sh), interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), 1.5)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def _tile(rng: np.random.Generator, size: int, sigma: float, aniso: float = 1.0) -> np.ndarray:
    """Zero-mean unit-std periodic noise, blurred (anisotropically for paper fibres)."""
    n = rng.standard_normal((size, size)).astype(np.float32)
    pad = int(4 * sigma * aniso) + 1
    n = np.pad(n, pad, mode="wrap")
    n = cv2.GaussianBlur(n, (0, 0), sigmaX=sigma * aniso, sigmaY=sigma)[pad:-pad, pad:-pad]
    return ((n - n.mean()) / (n.std() + 1e-6)).astype(np.float32)


# --------------------------------------------------------------------------------------- stroke drawing
def _stroke_mask(p: int, pts: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Coverage of a variable-width stroke (radius per point) along a dense polyline, (p, p) float32."""
    m = np.zeros((p, p), np.uint8)
    q = np.round(pts * 16).astype(np.int32)
    for i in range(len(pts)):
        r = max(8, int(round(radii[i] * 16)))
        cv2.circle(m, (int(q[i, 0]), int(q[i, 1])), r, 255, -1, cv2.LINE_AA, 4)
        if i + 1 < len(pts):
            t = max(1, int(round(2 * min(radii[i], radii[i + 1]))))
            cv2.line(m, (int(q[i, 0]), int(q[i, 1])), (int(q[i + 1, 0]), int(q[i + 1, 1])), 255, t,
                     cv2.LINE_AA, 4)
    return m.astype(np.float32) / 255.0


def _resample(pts: np.ndarray, step: float) -> np.ndarray:
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(s[-1] / max(step, 0.5)) + 1)
    t = np.linspace(0, s[-1], n)
    return np.stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])], axis=1)


def _smooth_path(pts: np.ndarray, window: int) -> np.ndarray:
    if window < 2:
        return pts
    k = np.ones(window) / window
    pad = np.pad(pts, ((window, window), (0, 0)), mode="edge")
    out = np.stack([np.convolve(pad[:, 0], k, "same"), np.convolve(pad[:, 1], k, "same")], axis=1)
    return out[window:-window]


def _marker_widths(rng: np.random.Generator, n: int, w: float) -> np.ndarray:
    """Stroke width along a marker stroke: slow pressure wobble, a slight taper at the lift-off end."""
    t = np.linspace(0, 1, n)
    wob = 1 + 0.1 * np.sin(2 * np.pi * (rng.uniform(0.5, 2.0) * t + rng.uniform(0, 1)))
    taper = 1 - rng.uniform(0.0, 0.25) * np.clip((t - 0.88) / 0.12, 0, 1)
    return w * wob * taper


def _polygon_mask(p: int, poly: np.ndarray) -> np.ndarray:
    m = np.zeros((p, p), np.uint8)
    cv2.fillPoly(m, [np.round(poly * 16).astype(np.int32)], 255, cv2.LINE_AA, 4)
    return m.astype(np.float32) / 255.0


def _ring_mask(p: int, c: np.ndarray, r_out: float, r_in: float, aspect: float, rot: float) -> np.ndarray:
    yy, xx = np.mgrid[0:p, 0:p].astype(np.float32)
    dx, dy = xx - c[0], yy - c[1]
    ca, sa = math.cos(rot), math.sin(rot)
    u, v = ca * dx + sa * dy, (-sa * dx + ca * dy) / aspect
    r = np.sqrt(u * u + v * v)
    return (np.clip(r_out - r + 0.5, 0, 1) * np.clip(r - r_in + 0.5, 0, 1)).astype(np.float32)


def _glyph_patch(glyph: np.ndarray, p: int, c: np.ndarray, radius: float, rot: float) -> np.ndarray:
    """Place a glyph mask in a (p, p) patch: centred at c, rotated, scaled so its ink fits `radius`."""
    gh, gw = glyph.shape
    ys, xs = np.nonzero(glyph > 0.5)
    gc = np.array([gw / 2, gh / 2])
    rmax = float(np.max(np.hypot(xs - gc[0], ys - gc[1]))) + 1
    a = (radius / rmax) * _rot2(rot)  # dst = a @ (src - gc) + c
    m = np.hstack([a, (c - a @ gc)[:, None]]).astype(np.float32)
    return cv2.warpAffine(glyph, m, (p, p), flags=cv2.INTER_LINEAR, borderValue=0.0)


# ------------------------------------------------------------------------------------------ mark shapes
def _triangle(rng: np.random.Generator, radius: float, rot: float) -> np.ndarray:
    """Vertices of a roughly equilateral triangle (all angles 42-88 deg) on a circle of `radius`."""
    while True:
        a, b = rng.normal(60, 9, 2)
        c = 180 - a - b
        if min(a, b, c) >= 42 and max(a, b, c) <= 88:
            break
    phis = np.array([0.0, 2 * math.radians(c), 2 * math.radians(c) + 2 * math.radians(a)]) + rot
    return np.stack([radius * np.cos(phis), radius * np.sin(phis)], axis=1)


def _x_angles(rng: np.random.Generator, card_roll: float) -> tuple[float, float]:
    """Directions of the two bars: crossing at 62-118 deg, never an upright '+' in the frame."""
    while True:
        cross = math.radians(rng.uniform(62, 118))
        base = rng.uniform(0, math.pi)
        a1, a2 = base, base + cross
        dev = [min((a + card_roll) % (math.pi / 2), math.pi / 2 - (a + card_roll) % (math.pi / 2)) for a in (a1, a2)]
        if max(dev) >= math.radians(24):  # otherwise it would read as an upright '+'
            return a1, a2


def _bow(rng: np.random.Generator, p0: np.ndarray, p1: np.ndarray, amount: float, n: int) -> np.ndarray:
    """A slightly curved segment from p0 to p1 (quadratic, mid-point pushed sideways by amount*length)."""
    d = p1 - p0
    nrm = np.array([-d[1], d[0]]) / (np.linalg.norm(d) + 1e-9)
    mid = (p0 + p1) / 2 + nrm * rng.uniform(-amount, amount) * np.linalg.norm(d)
    t = np.linspace(0, 1, n)[:, None]
    return (1 - t) ** 2 * p0 + 2 * (1 - t) * t * mid + t ** 2 * p1


# ------------------------------------------------------------------------------------------------ class
class BlindGenerator:
    """Renders frames of held cards with one mark (or none) as a phone/webcam would photograph them."""

    def __init__(self, seed: int = 0, width: int = 640, height: int = 480, plus_signs: bool = False) -> None:
        self._rng = np.random.default_rng(seed)
        self.width = width
        self.height = height
        # An upright "+" (a first-aid sign, a plus on a card) is, under the product's contract, an X turned by
        # 45 degrees: two crossed bars at any rotation. As written blind, the generator drew such signs in
        # mark-free frames, and the detector duly took them for X. By default a filled disc of the same extent
        # stands in their place (the same random draws, so the rest of every frame is unchanged);
        # `plus_signs=True` draws them, to measure how often the robot stops for a plus sign.
        self.plus_signs = plus_signs
        self._fibre = _tile(self._rng, 256, 0.7, 3.0)
        self._grain = _tile(self._rng, 256, 1.2)
        self._blotch = _tile(self._rng, 64, 4.0)
        self._white = self._rng.standard_normal((512, 512)).astype(np.float32)
        self._skin_srgb: tuple[float, ...] = (120.0, 165.0, 225.0)
        self._clean = False  # tests: render without blur, noise, mosaic, glare and JPEG

    # ------------------------------------------------------------------------------------- public API
    def frame(self, shape: Shape | None) -> tuple[np.ndarray, BlindLabel | None]:
        """BGR uint8 (height, width, 3); the label, or None for a mark-free frame."""
        rng = self._rng
        plan = self._plan(shape)
        bg = self._background(plan)
        cam = _Camera(rng.uniform(450, 800), self.width / 2 + rng.normal(0, 6), self.height / 2 + rng.normal(0, 6),
                      float(rng.uniform(-0.12, 0.04)) if rng.random() < 0.35 else 0.0)
        label: BlindLabel | None = None
        if plan.setting == "none":
            scene = _to_linear(bg)
            blur = self._blur_length(rng)
        else:
            scene, label = self._card_scene(plan, cam, bg)
            blur = self._blur_length(rng)
            if label is not None:
                label = BlindLabel(label.shape, label.box, label.size, label.tilt_deg, blur, label.finger_near,
                                   label.filled, label.style)
        return self._camera(scene, blur), label

    # -------------------------------------------------------------------------------------- planning
    def _plan(self, shape: Shape | None) -> _Plan:
        rng = self._rng
        cards = ((127, 76), (152, 102), (203, 127), (89, 64), (148, 105), (210, 148), (76, 76), (85, 55),
                 (100, 100), (180, 120))
        cw, ch = cards[int(rng.integers(len(cards)))]
        cw, ch = cw * rng.uniform(0.97, 1.03), ch * rng.uniform(0.97, 1.03)
        setting = str(rng.choice(["hand", "table", "wall"], p=[0.72, 0.14, 0.14]))
        if shape is None:
            if rng.random() < 0.4:
                return _Plan(None, "", False, "none", cw, ch)
            nonmark = str(rng.choice(["blank", "word", "square", "disc", "star", "check", "plus", "smiley"],
                                     p=[0.25, 0.15, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]))
            return _Plan(None, "", False, setting, cw, ch, nonmark=nonmark)
        shares = {Shape.O: {"marker": 0.5, "printed": 0.3, "sticker": 0.2},
                  Shape.X: {"marker": 0.45, "printed": 0.25, "tape": 0.2, "sticker": 0.1},
                  Shape.TRIANGLE: {"marker": 0.4, "printed": 0.25, "tape": 0.15, "sticker": 0.2}}[shape]
        style = str(rng.choice(list(shares), p=list(shares.values())))
        filled = False
        if shape is Shape.TRIANGLE:
            filled = {"sticker": True, "printed": rng.random() < 0.4, "marker": rng.random() < 0.25,
                      "tape": False}[style]
        return _Plan(shape, style, bool(filled), setting, cw, ch)

    @staticmethod
    def _target_size(rng: np.random.Generator) -> float:
        """Target longest side of the mark in the frame: many small (robot at 1-3 m), some large."""
        r = rng.random()
        if r < 0.55:
            return float(rng.uniform(38, 95))
        if r < 0.85:
            return float(rng.uniform(95, 200))
        return float(rng.uniform(200, 400))

    @staticmethod
    def _blur_length(rng: np.random.Generator) -> float:
        return float(rng.uniform(2, 20)) if rng.random() < 0.3 else 0.0

    # ----------------------------------------------------------------------------------- card scene
    def _card_scene(self, plan: _Plan, cam: _Camera, bg: np.ndarray) -> tuple[np.ndarray, BlindLabel | None]:
        rng = self._rng
        cw, ch = plan.card_w, plan.card_h
        short = min(cw, ch)
        # the mark (or non-mark) on the card: circumradius and centre, mm
        fill = rng.uniform(0.4, 0.96) if rng.random() < 0.75 else rng.uniform(0.25, 0.4)
        rho = 0.5 * short * fill - 1.2
        free_u, free_v = cw / 2 - rho - 1.5, ch / 2 - rho - 1.5
        mc = np.array([rng.uniform(-free_u, free_u) * rng.uniform(0.2, 1.0),
                       rng.uniform(-free_v, free_v) * rng.uniform(0.2, 1.0)])
        tilt = math.radians(rng.uniform(0, MAX_TILT_DEG) if rng.random() < 0.8 else rng.uniform(0, 15))
        roll = rng.uniform(-math.pi, math.pi) if plan.nonmark != "plus" else rng.uniform(-0.15, 0.15)
        if plan.nonmark == "word":
            roll = rng.uniform(-0.4, 0.4)
        size = self._target_size(rng)
        factor = {Shape.O: 1.0, Shape.X: 0.9, Shape.TRIANGLE: 0.85}.get(plan.shape, 1.0) if plan.shape else 1.0
        z = max(cam.f * 2 * rho * factor / size, 120.0)
        pose = self._pose(rng, tilt, roll, z, plan)
        hand_scale = rng.uniform(0.85, 1.15)
        margin = 80 * hand_scale if plan.setting == "hand" else 8.0
        k, ratio = self._texture_scale(cam, pose, cw, ch, margin)
        canvas = self._new_canvas(k, margin, cw, ch)
        canvas.ratio = ratio
        light_dir = rng.uniform(0, 2 * math.pi)
        mark_layers = self._mark_layers(plan, rho * k, roll) if plan.shape is not None else []
        if plan.shape is None and plan.nonmark != "blank":
            mark_layers = self._nonmark_layers(plan, rho * k)
        palm = self._build_canvas(canvas, plan, mc, rho, mark_layers, light_dir, hand_scale)
        self._place(cam, pose, canvas, mc, rho)
        frame_bg = bg.copy()
        if palm is not None:
            self._forearm(frame_bg, cam, pose, canvas, palm)
        scene = _to_linear(frame_bg)
        scene = self._composite(scene, cam, pose, canvas, plan, light_dir)
        if plan.shape is None:
            return scene, None
        return scene, self._label(plan, tilt)

    def _pose(self, rng: np.random.Generator, tilt: float, roll: float, z: float, plan: _Plan) -> _Pose:
        axis_a = rng.uniform(0, 2 * math.pi)
        axis = np.array([math.cos(axis_a), math.sin(axis_a), 0.0])
        r_tilt = cv2.Rodrigues(axis * tilt)[0]
        r_roll = cv2.Rodrigues(np.array([0.0, 0.0, roll]))[0]
        r = r_tilt @ r_roll
        curl = 0.0
        if rng.random() < 0.3:
            curl = float(rng.choice([-1, 1]) / rng.uniform(2.5, 8.0) / max(plan.card_w, plan.card_h))
        return _Pose(r[:, 0].copy(), r[:, 1].copy(), r[:, 2].copy(), np.array([0.0, 0.0, z]), curl,
                     int(rng.integers(2)))

    def _texture_scale(self, cam: _Camera, pose: _Pose, cw: float, ch: float, margin: float
                       ) -> tuple[float, float]:
        """Texture pixels per mm: about 1.6x the frame's sampling at the card, capped for speed."""
        corners = [pose.origin + su * cw / 2 * pose.ex + sv * ch / 2 * pose.ey for su in (-1, 1) for sv in (-1, 1)]
        znear = max(60.0, min(float(c[2]) for c in corners))
        k = 1.35 * cam.f / znear
        span = max(cw, ch) + 2 * margin
        k = float(min(k, 900 / span, 14.0))
        return k, k / (cam.f / znear)

    def _new_canvas(self, k: float, margin: float, cw: float, ch: float) -> _Canvas:
        w = int(math.ceil((cw + 2 * margin) * k))
        h = int(math.ceil((ch + 2 * margin) * k))
        return _Canvas(k, margin, cw, ch, np.zeros((h, w, 4), np.float32), np.zeros((h, w, 3), np.float32))

    # ------------------------------------------------------------------------------ canvas building
    def _build_canvas(self, cv: _Canvas, plan: _Plan, mc: np.ndarray, rho: float, layers: list[_Layer],
                      light_dir: float, hand_scale: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Paint hand (behind), card, mark, lighting, hand (front). Returns palm centre + outward dir, mm."""
        rng = self._rng
        h, w = cv.alpha.shape
        card_mask = self._card_mask(cv, rng)
        cv.card[:] = card_mask
        albedo = self._paper(cv, rng, mc, rho)
        for lay in layers:
            self._apply_layer(albedo, cv, lay, mc)
        light = self._light_field(cv, rng, light_dir)
        front = np.zeros((h, w), np.float32)
        front_col = np.zeros((h, w, 3), np.float32)
        back = np.zeros((h, w), np.float32)
        back_col = np.zeros((h, w, 3), np.float32)
        palm = None
        if plan.setting == "hand":
            palm = self._hand(cv, rng, mc, rho, hand_scale, (front, front_col, back, back_col), plan)
        elif plan.setting == "wall":
            self._pins(cv, rng, front, front_col)
        fx, fy, fw, fh = cv2.boundingRect((front > 0).view(np.uint8))
        if fw > 0:  # cast shadow of the front hand (or pins) onto the card
            off = np.array([math.cos(light_dir), math.sin(light_dir)]) * rng.uniform(2, 7) * cv.k
            m = np.float32([[1, 0, -off[0]], [0, 1, -off[1]]])
            sh = _soft(cv2.warpAffine(front, m, (w, h)), max(1.0, rng.uniform(2, 5) * cv.k))
            light *= 1 - rng.uniform(0.25, 0.5) * sh
        lit = albedo
        lit *= light[..., None]
        glare = self._glare(cv, rng, plan)
        if glare is not None:
            lit += glare[..., None]
        cv.colour[:] = lit
        cv.alpha[:] = card_mask
        bx, by, bw, bh = cv2.boundingRect((back > 0).view(np.uint8))
        if bw > 0:  # the hand behind the card shows where the card is not
            sl = np.s_[by:by + bh, bx:bx + bw]
            a = (back[sl] * (1 - card_mask[sl]))
            cv.colour[sl] = cv.colour[sl] * (1 - a[..., None]) + back_col[sl] * a[..., None]
            cv.alpha[sl] = np.maximum(card_mask[sl], back[sl])
            cv.hand[sl] = a
        if fw > 0:  # the front of the hand over everything
            sl = np.s_[fy:fy + fh, fx:fx + fw]
            a = front[sl]
            cv.colour[sl] = cv.colour[sl] * (1 - a[..., None]) + front_col[sl] * a[..., None]
            cv.alpha[sl] = np.maximum(cv.alpha[sl], a)
            cv.hand[sl] = np.maximum(cv.hand[sl], a)
        return palm

    def _card_mask(self, cv: _Canvas, rng: np.random.Generator) -> np.ndarray:
        h, w = cv.alpha.shape
        m = np.zeros((h, w), np.uint8)
        x0, y0 = cv.px(-cv.card_w / 2, -cv.card_h / 2)
        x1, y1 = cv.px(cv.card_w / 2, cv.card_h / 2)
        r = rng.uniform(0, 4) * cv.k if rng.random() < 0.6 else 0.5 * cv.k
        r = min(r, 0.2 * (x1 - x0))
        pts = []
        for cx, cy, a0 in ((x1 - r, y1 - r, 0), (x0 + r, y1 - r, 90), (x0 + r, y0 + r, 180), (x1 - r, y0 + r, 270)):
            for a in np.radians(np.linspace(a0, a0 + 90, 8)):
                pts.append((cx + r * math.cos(a), cy + r * math.sin(a)))
        cv2.fillPoly(m, [np.round(np.array(pts) * 16).astype(np.int32)], 255, cv2.LINE_AA, 4)
        return m.astype(np.float32) / 255.0

    def _paper(self, cv: _Canvas, rng: np.random.Generator, mc: np.ndarray, rho: float) -> np.ndarray:
        """Paper albedo (linear): base colour, fibres, blotches, rules/grid, creases, corner word."""
        h, w = cv.alpha.shape
        base = _PAPERS[int(rng.integers(len(_PAPERS)))]
        img = np.empty((h, w, 3), np.uint8)
        img[:] = _jitter(rng, base, 3)
        kind = rng.random()
        x0, y0 = cv.px(-cv.card_w / 2, -cv.card_h / 2)
        x1, y1 = cv.px(cv.card_w / 2, cv.card_h / 2)
        thin = max(1, int(round(0.25 * cv.k)))
        if kind < 0.2:  # ruled notebook paper
            line_c = _jitter(rng, (215, 190, 160), 10)
            step = rng.uniform(6, 8.5) * cv.k
            y = y0 + rng.uniform(8, 15) * cv.k
            while y < y1:
                cv2.line(img, (int(x0), int(y)), (int(x1), int(y)), line_c, thin, cv2.LINE_AA)
                y += step
            if rng.random() < 0.5:
                xm = int(x0 + rng.uniform(10, 25) * cv.k)
                cv2.line(img, (xm, int(y0)), (xm, int(y1)), _jitter(rng, (180, 170, 235), 10), thin, cv2.LINE_AA)
        elif kind < 0.32:  # faint grid
            line_c = _jitter(rng, (220, 215, 200), 8)
            step = rng.uniform(4, 6) * cv.k
            for x in np.arange(x0 + step, x1, step):
                cv2.line(img, (int(x), int(y0)), (int(x), int(y1)), line_c, thin)
            for y in np.arange(y0 + step, y1, step):
                cv2.line(img, (int(x0), int(y)), (int(x1), int(y)), line_c, thin)
        if rng.random() < 0.3:
            self._corner_word(img, cv, rng, mc, rho)
        lin = _to_linear(img)
        fib = _noise_crop(self._fibre, rng, h, w)
        blot = _noise_crop(self._blotch, rng, h, w, scale=rng.uniform(2, 6))
        lin *= (1 + 0.025 * fib + 0.02 * blot)[..., None]
        if rng.random() < 0.25:
            lin *= self._crease(cv, rng)[..., None]
        return lin

    def _corner_word(self, img: np.ndarray, cv: _Canvas, rng: np.random.Generator, mc: np.ndarray,
                     rho: float) -> None:
        """A small printed word in the card corner farthest from the mark, if it stays clear of it."""
        su = -1 if mc[0] > 0 else 1
        sv = -1 if mc[1] > 0 else 1
        text = _CORNER_WORDS[int(rng.integers(len(_CORNER_WORDS)))]
        px = max(6, int(rng.uniform(2.5, 4.5) * cv.k))
        m = _text_mask(text, FONTS[int(rng.integers(len(FONTS)))], px)
        mh, mw = m.shape
        cu = su * (cv.card_w / 2 - 4) - (mw / cv.k if su > 0 else 0)
        cvv = sv * (cv.card_h / 2 - 4) - (mh / cv.k if sv > 0 else 0)
        box_far = (abs(cu + mw / cv.k / 2 - mc[0]) > rho + mw / cv.k / 2 + 3
                   or abs(cvv + mh / cv.k / 2 - mc[1]) > rho + mh / cv.k / 2 + 3)
        if box_far and mw / cv.k < cv.card_w * 0.6:
            x, y = cv.px(cu, cvv)
            _put_mask(img, m, int(x), int(y), _jitter(rng, (110, 110, 110), 40))

    def _crease(self, cv: _Canvas, rng: np.random.Generator) -> np.ndarray:
        h, w = cv.alpha.shape
        a = rng.uniform(0, math.pi)
        cx, cy = rng.uniform(0.2, 0.8) * w, rng.uniform(0.2, 0.8) * h
        d = self._ramp(h, w, cx, cy, a)
        width = rng.uniform(0.6, 1.5) * cv.k
        side = np.where(d > 0, rng.uniform(0.96, 1.0), rng.uniform(1.0, 1.03))
        return (side * (1 - 0.06 * np.exp(-(d / width) ** 2))).astype(np.float32)

    def _light_field(self, cv: _Canvas, rng: np.random.Generator, light_dir: float) -> np.ndarray:
        h, w = cv.alpha.shape
        d = self._ramp(h, w, w / 2, h / 2, light_dir) / max(w, h)
        g = rng.uniform(0.0, 0.5)
        return (rng.uniform(0.85, 1.1) * (1 - g * d)).astype(np.float32)

    def _glare(self, cv: _Canvas, rng: np.random.Generator, plan: _Plan) -> np.ndarray | None:
        if self._clean or rng.random() > 0.18:
            return None
        h, w = cv.alpha.shape
        cx, cy = cv.px(rng.uniform(-0.5, 0.5) * cv.card_w, rng.uniform(-0.5, 0.5) * cv.card_h)
        sx, sy = rng.uniform(0.1, 0.35) * cv.card_w * cv.k, rng.uniform(0.05, 0.25) * cv.card_h * cv.k
        a = rng.uniform(0, math.pi)
        u, v = self._ramp(h, w, cx, cy, a), self._ramp(h, w, cx, cy, a + math.pi / 2)
        return (rng.uniform(0.15, 0.6) * np.exp(-0.5 * ((u / sx) ** 2 + (v / sy) ** 2))).astype(np.float32)

    @staticmethod
    def _ramp(h: int, w: int, cx: float, cy: float, angle: float) -> np.ndarray:
        """Signed distance along direction `angle` from (cx, cy), for every pixel of an (h, w) image."""
        xs = (np.arange(w, dtype=np.float32) - cx) * math.cos(angle)
        ys = (np.arange(h, dtype=np.float32) - cy) * math.sin(angle)
        return ys[:, None] + xs[None, :]

    def _apply_layer(self, albedo: np.ndarray, cv: _Canvas, lay: _Layer, mc: np.ndarray) -> None:
        p = lay.mask.shape[0]
        cx, cy = cv.px(float(mc[0]), float(mc[1]))
        x, y = int(round(cx - p / 2)), int(round(cy - p / 2))
        h, w = cv.alpha.shape
        x0, y0, x1, y1 = max(0, x), max(0, y), min(w, x + p), min(h, y + p)
        m = lay.mask[y0 - y:y1 - y, x0 - x:x1 - x]
        roi = albedo[y0:y1, x0:x1]
        a = (m * lay.opacity)[..., None]
        if lay.mode == "sub":
            roi *= 1 - a * (1 - lay.colour)
        elif lay.mode == "cover":
            roi[:] = roi * (1 - a) + lay.colour * a
        elif lay.mode == "shadow":
            roi *= 1 - a
        elif lay.mode == "gloss":
            roi += a * lay.colour
        if lay.is_ink:
            np.maximum(cv.ink[y0:y1, x0:x1], (m > 0.5).astype(np.float32), out=cv.ink[y0:y1, x0:x1])

    # ----------------------------------------------------------------------------------------- marks
    def _ink_colour(self, rng: np.random.Generator, names: tuple[str, ...] | None = None) -> np.ndarray:
        keys = names or tuple(_INKS)
        return _lin(_jitter(rng, _INKS[keys[int(rng.integers(len(keys)))]], 10))

    def _mark_layers(self, plan: _Plan, radius: float, roll: float) -> list[_Layer]:
        """The mark as layers in a square patch centred on the mark; `radius` is its circumradius, px."""
        rng = self._rng
        p = int(math.ceil(2 * radius + 8))
        c = np.array([p / 2, p / 2])
        shape, style = plan.shape, plan.style
        if style == "marker":
            return self._marker_mark(rng, shape, p, c, radius, roll, plan.filled)
        if style == "printed":
            return self._printed_mark(rng, shape, p, c, radius, roll, plan.filled)
        if style == "tape":
            return self._tape_mark(rng, shape, p, c, radius, roll)
        return self._sticker_mark(rng, shape, p, c, radius, roll)

    def _marker_stroke(self, rng: np.random.Generator, p: int, pts: np.ndarray, w: float, colour: np.ndarray,
                       opacity: float) -> list[_Layer]:
        pts = _resample(pts, max(1.0, w * 0.3))
        widths = _marker_widths(rng, len(pts), w)
        layers = [_Layer(_stroke_mask(p, pts, widths / 2), colour, opacity, "sub")]
        pool = np.zeros((p, p), np.uint8)
        for end, wd in ((pts[0], widths[0]), (pts[-1], widths[-1])):
            r = wd * rng.uniform(0.35, 0.55)
            cv2.circle(pool, (int(end[0] * 16), int(end[1] * 16)), max(1, int(r * 16)), 255, -1, cv2.LINE_AA, 4)
        layers.append(_Layer(pool.astype(np.float32) / 255.0, colour, rng.uniform(0.2, 0.45), "sub", False))
        return layers

    def _marker_mark(self, rng: np.random.Generator, shape: Shape | None, p: int, c: np.ndarray, radius: float,
                     roll: float, filled: bool) -> list[_Layer]:
        colour = self._ink_colour(rng)
        opacity = rng.uniform(0.8, 0.97)
        if shape is Shape.O:
            frac = rng.uniform(0.09, 0.2)
            w = frac * 2 * radius
            rc = radius - w / 2 - 1
            aspect = rng.uniform(0.86, 1.0)
            rot = rng.uniform(0, math.pi)
            start = rng.uniform(0, 2 * math.pi)
            sweep = 2 * math.pi + rng.uniform(-0.2, 0.45)
            th = start + np.linspace(0, sweep, 200) * rng.choice([-1, 1])
            t = np.linspace(0, 1, 200)
            rr = rc * (1 + 0.025 * np.sin(2 * th + rng.uniform(0, 6)) + rng.uniform(-0.06, 0.0) * t)
            local = np.stack([rr * np.cos(th), rr * np.sin(th) * aspect], axis=1) @ _rot2(rot).T
            return self._marker_stroke(rng, p, c + local, w, colour, opacity)
        if shape is Shape.TRIANGLE:
            w = rng.uniform(0.07, 0.17) * 2 * radius
            verts = _triangle(rng, radius - w / 2 - 1, rng.uniform(0, 2 * math.pi))
            layers: list[_Layer] = []
            if filled:
                fillm = _polygon_mask(p, c + verts * 0.97)
                yy, xx = np.mgrid[0:p, 0:p].astype(np.float32)
                a = rng.uniform(0, math.pi)
                hatch = 0.5 + 0.5 * np.sin((xx * math.cos(a) + yy * math.sin(a)) / max(1.5, w * 0.35))
                layers.append(_Layer(fillm * (0.78 + 0.22 * hatch), colour, opacity, "sub"))
            n = 60
            side_pts = [_bow(rng, verts[i], verts[(i + 1) % 3], 0.04, n) for i in range(3)]
            if rng.random() < 0.6:  # one continuous stroke, corners rounded, closing with an overshoot
                path = np.concatenate(side_pts + [side_pts[0][: int(n * rng.uniform(0.02, 0.2))]])
                path = _smooth_path(_resample(path, 1.0), max(1, int(w * rng.uniform(0.3, 0.8))))
                layers += self._marker_stroke(rng, p, c + path, w, colour, opacity)
            else:  # three strokes overlapping at the corners
                for sp in side_pts:
                    d = sp[-1] - sp[0]
                    ext = d / (np.linalg.norm(d) + 1e-9) * w * rng.uniform(0.0, 0.4)
                    layers += self._marker_stroke(rng, p, c + np.concatenate([[sp[0] - ext], sp, [sp[-1] + ext]]),
                                                  w, colour, opacity)
            return layers
        # X: two slightly curved bars crossing near their middles
        a1, a2 = _x_angles(rng, roll)
        layers = []
        for a in (a1, a2):
            half = (radius - 1) * rng.uniform(0.88, 1.0)
            ratio = rng.uniform(0.07, 0.18)
            w = ratio * 2 * half
            half -= w / 2
            d = np.array([math.cos(a), math.sin(a)])
            off = d * rng.uniform(-0.08, 0.08) * half
            p0, p1 = c + off - d * half, c + off + d * half
            if rng.random() < 0.5:
                p0, p1 = p1, p0
            layers += self._marker_stroke(rng, p, _bow(rng, p0, p1, 0.04, 50), w, colour, opacity)
        return layers

    def _printed_mark(self, rng: np.random.Generator, shape: Shape | None, p: int, c: np.ndarray, radius: float,
                      roll: float, filled: bool) -> list[_Layer]:
        colour = self._ink_colour(rng, ("black", "black", "navy", "red", "dark_green", "blue", "purple"))
        rot = rng.uniform(0, 2 * math.pi)
        if shape is Shape.O:
            frac = rng.uniform(0.1, 0.2)
            m = _ring_mask(p, c, radius - 1, (radius - 1) * (1 - 2 * frac), 1.0, 0.0)
        elif shape is Shape.TRIANGLE:
            glyph = _glyph("\u25b2" if filled else "\u25b3") if rng.random() < 0.5 else None
            if glyph is not None:
                m = _glyph_patch(glyph, p, c, radius - 1, rot)
            else:
                w = rng.uniform(0.06, 0.14) * 2 * radius
                verts = _triangle(rng, radius - w / 2 - 1, rot)
                if filled:
                    m = _polygon_mask(p, c + _triangle(rng, radius - 1, rot))
                else:
                    mu = np.zeros((p, p), np.uint8)
                    cv2.polylines(mu, [np.round((c + verts) * 16).astype(np.int32)], True, 255,
                                  max(1, int(round(w))), cv2.LINE_AA, 4)
                    m = mu.astype(np.float32) / 255.0
        else:
            a1, a2 = _x_angles(rng, roll)
            glyph = _glyph("\u2715") if rng.random() < 0.5 else None
            if glyph is not None and abs(((a2 - a1) % math.pi) - math.pi / 2) < 0.6:
                m = _glyph_patch(glyph, p, c, radius - 1, a1 - math.pi / 4)
            else:
                m = np.zeros((p, p), np.float32)
                for a in (a1, a2):
                    half = radius - 1
                    w = rng.uniform(0.08, 0.18) * 2 * half
                    d, nrm = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
                    hl = math.sqrt(max(half ** 2 - (w / 2) ** 2, 1.0))
                    poly = np.array([c - d * hl - nrm * w / 2, c + d * hl - nrm * w / 2, c + d * hl + nrm * w / 2,
                                     c - d * hl + nrm * w / 2])
                    m = np.maximum(m, _polygon_mask(p, poly))
        return [_Layer(m, colour, rng.uniform(0.93, 1.0), "sub")]

    def _tape_strip(self, rng: np.random.Generator, p: int, p0: np.ndarray, p1: np.ndarray, w: float) -> np.ndarray:
        """Polygon of a tape strip from p0 to p1 with torn (zig-zag) ends."""
        d = (p1 - p0) / (np.linalg.norm(p1 - p0) + 1e-9)
        nrm = np.array([-d[1], d[0]])
        k = int(rng.integers(4, 8))
        s = np.linspace(-0.5, 0.5, k)
        end1 = [p1 + nrm * si * w + d * rng.uniform(-0.25, 0.0) * w for si in s]
        end0 = [p0 + nrm * si * w + d * rng.uniform(0.0, 0.25) * w for si in s[::-1]]
        return np.array(end1 + end0)

    def _tape_mark(self, rng: np.random.Generator, shape: Shape | None, p: int, c: np.ndarray, radius: float,
                   roll: float) -> list[_Layer]:
        colour = self._ink_colour(rng, ("red", "blue", "green", "black", "orange", "purple", "navy", "magenta"))
        opacity = rng.uniform(0.86, 0.95)
        strips: list[tuple[np.ndarray, np.ndarray, float]] = []
        if shape is Shape.TRIANGLE:
            w = rng.uniform(0.09, 0.16) * 2 * radius
            verts = _triangle(rng, radius - w - 1, rng.uniform(0, 2 * math.pi))
            for i in range(3):
                a, b = verts[i], verts[(i + 1) % 3]
                d = (b - a) / np.linalg.norm(b - a)
                strips.append((c + a - d * w * 0.45, c + b + d * w * 0.45, w))
        else:
            for a in _x_angles(rng, roll):
                d = np.array([math.cos(a), math.sin(a)])
                w = rng.uniform(0.11, 0.19) * 2 * radius
                half = math.sqrt(max((radius - 1) ** 2 - (w / 2) ** 2, 1.0)) - 0.25 * w
                off = d * rng.uniform(-0.06, 0.06) * half
                strips.append((c + off - d * half, c + off + d * half, w))
        layers: list[_Layer] = []
        white = np.ones(3, np.float32)
        for p0, p1, w in strips:
            m = _polygon_mask(p, self._tape_strip(rng, p, p0, p1, w))
            layers.append(_Layer(m, colour, opacity, "cover"))
            sheen = np.zeros((p, p), np.uint8)
            d = (p1 - p0) / np.linalg.norm(p1 - p0)
            nrm = np.array([-d[1], d[0]]) * rng.uniform(-0.3, 0.3) * w
            cv2.line(sheen, tuple(np.round(p0 + nrm).astype(int)), tuple(np.round(p1 + nrm).astype(int)), 255,
                     max(1, int(w * 0.2)))
            sh = cv2.GaussianBlur(sheen.astype(np.float32) / 255.0, (0, 0), max(1.0, w * 0.15)) * m
            layers.append(_Layer(sh, white, rng.uniform(0.05, 0.2), "gloss", False))
        return layers

    def _sticker_mark(self, rng: np.random.Generator, shape: Shape | None, p: int, c: np.ndarray, radius: float,
                      roll: float) -> list[_Layer]:
        colour = self._ink_colour(rng, ("red", "blue", "green", "orange", "purple", "black", "magenta", "teal"))
        if shape is Shape.O:
            frac = rng.uniform(0.12, 0.21)
            m = _ring_mask(p, c, radius - 2, (radius - 2) * (1 - 2 * frac), 1.0, 0.0)
        elif shape is Shape.TRIANGLE:
            verts = _triangle(rng, radius - 2, rng.uniform(0, 2 * math.pi))
            verts = verts + rng.normal(0, 0.01 * radius, verts.shape)
            m = _polygon_mask(p, c + verts)
        else:
            m = np.zeros((p, p), np.float32)
            for a in _x_angles(rng, roll):
                d, nrm = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
                w = rng.uniform(0.12, 0.19) * 2 * radius
                hl = math.sqrt(max((radius - 2) ** 2 - (w / 2) ** 2, 1.0))
                poly = np.array([c - d * hl - nrm * w / 2, c + d * hl - nrm * w / 2, c + d * hl + nrm * w / 2,
                                 c - d * hl + nrm * w / 2])
                m = np.maximum(m, _polygon_mask(p, poly))
        shift = rng.uniform(0.5, 2.0)
        sh = cv2.warpAffine(m, np.float32([[1, 0, shift], [0, 1, shift * rng.uniform(-1, 1)]]), (p, p))
        sh = cv2.GaussianBlur(sh, (0, 0), max(0.8, shift)) * (1 - m)
        tex = 1 + 0.03 * _noise_crop(self._grain, rng, p, p)
        return [_Layer(sh, np.zeros(3, np.float32), rng.uniform(0.15, 0.35), "shadow", False),
                _Layer(m * (0.97 + 0.03 * tex), colour, 1.0, "cover")]

    def _nonmark_layers(self, plan: _Plan, radius: float) -> list[_Layer]:
        """Things on a card that share part of a mark's look but fail the definition."""
        rng = self._rng
        p = int(math.ceil(2 * radius + 8))
        c = np.array([p / 2, p / 2])
        colour = self._ink_colour(rng)
        w = max(2.0, rng.uniform(0.07, 0.15) * 2 * radius)
        kind = plan.nonmark
        mu = np.zeros((p, p), np.uint8)
        q = lambda pts: np.round(pts * 16).astype(np.int32)  # noqa: E731
        if kind == "word":
            text = _WORDS_SAFE[int(rng.integers(len(_WORDS_SAFE)))]
            tm = _text_mask(text, FONTS[int(rng.integers(len(FONTS)))], 64).astype(np.float32) / 255.0
            s = min(1.8 * radius / tm.shape[1], 0.8 * radius / tm.shape[0])
            tm = cv2.resize(tm, None, fx=s, fy=s, interpolation=cv2.INTER_AREA)
            y, x = int(c[1] - tm.shape[0] / 2), int(c[0] - tm.shape[1] / 2)
            m = np.zeros((p, p), np.float32)
            m[y:y + tm.shape[0], x:x + tm.shape[1]] = tm[: p - y, : p - x]
            return [_Layer(m, colour, 0.95, "sub", False)]
        if kind == "square":
            r = radius * 0.7
            poly = c + np.array([[-r, -r], [r, -r], [r, r], [-r, r]]) @ _rot2(rng.uniform(0, 1.5)).T
            if rng.random() < 0.5:
                cv2.polylines(mu, [q(poly)], True, 255, max(1, int(w)), cv2.LINE_AA, 4)
            else:
                cv2.fillPoly(mu, [q(poly)], 255, cv2.LINE_AA, 4)
        elif kind == "disc":
            cv2.circle(mu, (int(c[0] * 16), int(c[1] * 16)), int(radius * 0.9 * 16), 255, -1, cv2.LINE_AA, 4)
        elif kind == "star":
            ang = np.arange(10) * math.pi / 5 + rng.uniform(0, math.pi)
            rr = np.where(np.arange(10) % 2 == 0, radius * 0.95, radius * 0.4)
            poly = c + np.stack([rr * np.cos(ang), rr * np.sin(ang)], axis=1)
            if rng.random() < 0.5:
                cv2.fillPoly(mu, [q(poly)], 255, cv2.LINE_AA, 4)
            else:
                cv2.polylines(mu, [q(poly)], True, 255, max(1, int(w * 0.6)), cv2.LINE_AA, 4)
        elif kind == "check":
            pts = c + np.array([[-0.7, 0.0], [-0.2, 0.6], [0.8, -0.7]]) * radius
            cv2.polylines(mu, [q(pts)], False, 255, max(1, int(w)), cv2.LINE_AA, 4)
        elif kind == "plus":
            a = rng.uniform(-0.15, 0.15)
            if not self.plus_signs:  # a disc in its place (see __init__)
                cv2.circle(mu, (int(c[0] * 16), int(c[1] * 16)), int(radius * 0.6 * 16), 255, -1, cv2.LINE_AA, 4)
            else:
                for d in (np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])):
                    cv2.line(mu, tuple(q(c - d * radius * 0.85)), tuple(q(c + d * radius * 0.85)), 255,
                             max(1, int(w)), cv2.LINE_AA, 4)
        else:  # smiley: a ring with eyes and a mouth inside (the hole is not empty)
            cv2.circle(mu, (int(c[0] * 16), int(c[1] * 16)), int((radius - w / 2 - 1) * 16), 255, max(1, int(w)),
                       cv2.LINE_AA, 4)
            for ex in (-0.35, 0.35):
                cv2.circle(mu, (int((c[0] + ex * radius) * 16), int((c[1] - 0.25 * radius) * 16)),
                           int(radius * 0.12 * 16), 255, -1, cv2.LINE_AA, 4)
            cv2.ellipse(mu, (int(c[0] * 16), int((c[1] + 0.05 * radius) * 16)),
                        (int(radius * 0.45 * 16), int(radius * 0.35 * 16)), 0, 20, 160, 255, max(1, int(w * 0.7)),
                        cv2.LINE_AA, 4)
        return [_Layer(mu.astype(np.float32) / 255.0, colour, rng.uniform(0.85, 0.97), "sub", False)]

    # ------------------------------------------------------------------------------------------ hand
    def _hand(self, cv: _Canvas, rng: np.random.Generator, mc: np.ndarray, rho: float, hs: float,
              bufs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], plan: _Plan
              ) -> tuple[np.ndarray, np.ndarray]:
        """A hand holding the card at an edge or corner; thumb (or fingertips) on the front."""
        front, front_col, back, back_col = bufs
        skin = np.asarray(_SKINS[int(rng.integers(len(_SKINS)))], float)
        skin = skin + (np.asarray(_SKINS[int(rng.integers(len(_SKINS)))], float) - skin) * rng.uniform(0, 0.5)
        skin_lin = _lin(np.clip(skin + rng.normal(0, 6, 3), 0, 255))
        hw, hh = cv.card_w / 2, cv.card_h / 2
        if rng.random() < 0.75:  # an edge
            side = int(rng.choice(4, p=[0.3, 0.3, 0.25, 0.15]))  # right, left, bottom, top
            o = np.array([[1, 0], [-1, 0], [0, 1], [0, -1]][side], float)
            tau = np.array([-o[1], o[0]])
            extent = hh if side < 2 else hw
            e = o * (hw if side < 2 else hh) + tau * rng.uniform(-0.6, 0.6) * extent
        else:  # a corner
            su, sv = rng.choice([-1, 1]), rng.choice([-1, 1])
            o = np.array([su, sv], float) / math.sqrt(2)
            tau = np.array([-o[1], o[0]])
            e = np.array([su * hw, sv * hh]) - o * 3
        palm_c = e + o * 34 * hs + tau * rng.uniform(-8, 8) * hs
        # palm and fingers behind the card (visible only outside it)
        # the palm seen from its back: narrower at the wrist, wide at the knuckles near the card's edge
        self._capsule_part(cv, back, back_col, palm_c + o * 22 * hs, palm_c - o * 6 * hs, 23 * hs, 30 * hs,
                           skin_lin * 0.97, False, rng)
        self._skin_srgb = tuple(float(x) for x in skin)
        nf = int(rng.integers(1, 5))
        for i in range(nf):
            off = (i - (nf - 1) / 2) * 17 * hs + rng.normal(0, 2)
            base = palm_c + tau * off - o * 18 * hs
            tip = e + tau * off - o * rng.uniform(5, 25) * hs
            self._capsule_part(cv, back, back_col, base, tip, 8.5 * hs, 8 * hs, skin_lin, False, rng)
        grip = rng.random()
        if grip < 0.65:  # thumb on the front
            base = e + o * 12 * hs + tau * rng.choice([-1, 1]) * rng.uniform(10, 22) * hs
            to_mark = mc - base
            toward = to_mark / (np.linalg.norm(to_mark) + 1e-9)
            if rng.random() < 0.35 and float(np.dot(toward, -o)) > 0.6:
                direction = toward
                gap = rng.uniform(-0.08, 0.2) * 2 * rho
                length = min(float(np.linalg.norm(to_mark)) - rho - 9 * hs - gap, 80 * hs)
            else:
                ang = rng.uniform(-0.6, 0.6)
                direction = _rot2(ang) @ (-o)
                length = rng.uniform(28, 60) * hs
            length = max(length, 18 * hs)
            tip = base + direction * length
            tip = self._retract(tip, base, mc, rho, 9 * hs)
            self._capsule_part(cv, front, front_col, base, tip, 11 * hs, 9 * hs, skin_lin, True, rng)
        elif grip < 0.85:  # 1-3 fingertips on the front
            for _ in range(int(rng.integers(1, 4))):
                off = rng.uniform(-1, 1) * 20 * hs
                base = e + o * 25 * hs + tau * off
                tip = e - o * rng.uniform(6, 22) * hs + tau * (off + rng.normal(0, 3))
                tip = self._retract(tip, base, mc, rho, 8 * hs)
                self._capsule_part(cv, front, front_col, base, tip, 9 * hs, 8 * hs, skin_lin, True, rng)
        # else: the thumb is behind the card too
        return palm_c + o * 10 * hs, o

    @staticmethod
    def _retract(tip: np.ndarray, base: np.ndarray, mc: np.ndarray, rho: float, r: float) -> np.ndarray:
        """Pull a fingertip back so that it covers at most a sliver of the mark (~10 % of its radius)."""
        for _ in range(30):
            if np.linalg.norm(tip - mc) - r > 0.8 * rho or np.linalg.norm(tip - base) < 12:
                break
            tip = tip + (base - tip) * 0.08
        return tip

    def _part_roi(self, cv: _Canvas, pts_mm: list[np.ndarray], pad_mm: float) -> tuple[int, int, int, int]:
        h, w = cv.alpha.shape
        px = np.array([cv.px(float(p[0]), float(p[1])) for p in pts_mm])
        pad = pad_mm * cv.k
        x0, y0 = np.floor(px.min(axis=0) - pad).astype(int)
        x1, y1 = np.ceil(px.max(axis=0) + pad).astype(int)
        return max(0, x0), max(0, y0), min(w, x1), min(h, y1)

    def _shade_part(self, cv: _Canvas, buf: np.ndarray, col: np.ndarray, mask: np.ndarray, roi: tuple[int, ...],
                    radius_px: float, skin: np.ndarray, nail: np.ndarray | None) -> None:
        """Composite one skin part: darker at its silhouette (a rounded finger), lighter nail on top."""
        x0, y0, x1, y1 = roi
        if x1 <= x0 or y1 <= y0:
            return
        blur = _soft(mask, max(1.0, radius_px * 0.5))
        shade = 0.55 + 0.45 * np.sqrt(np.clip((blur - 0.3) / 0.7, 0, 1))
        c = skin[None, None, :] * shade[..., None]
        if nail is not None:
            nl = nail[..., None] * 0.75
            c = c * (1 - nl) + np.minimum(1.0, skin * 1.35 + 0.06)[None, None, :] * shade[..., None] * nl
        a = mask[..., None]
        col[y0:y1, x0:x1] = col[y0:y1, x0:x1] * (1 - a) + c * a
        np.maximum(buf[y0:y1, x0:x1], mask, out=buf[y0:y1, x0:x1])

    def _capsule_part(self, cv: _Canvas, buf: np.ndarray, col: np.ndarray, base: np.ndarray, tip: np.ndarray,
                      r0: float, r1: float, skin: np.ndarray, nail: bool, rng: np.random.Generator) -> None:
        roi = self._part_roi(cv, [base, tip], max(r0, r1) + 2)
        x0, y0, x1, y1 = roi
        if x1 <= x0 or y1 <= y0:
            return
        m = np.zeros((y1 - y0, x1 - x0), np.uint8)
        b = np.array(cv.px(float(base[0]), float(base[1]))) - (x0, y0)
        t = np.array(cv.px(float(tip[0]), float(tip[1]))) - (x0, y0)
        d = (t - b) / (np.linalg.norm(t - b) + 1e-9)
        nrm = np.array([-d[1], d[0]])
        rb, rt = r0 * cv.k, r1 * cv.k
        poly = np.array([b + nrm * rb, t + nrm * rt, t - nrm * rt, b - nrm * rb])
        cv2.fillConvexPoly(m, np.round(poly * 16).astype(np.int32), 255, cv2.LINE_AA, 4)
        for q, r in ((b, rb), (t, rt)):
            cv2.circle(m, (int(q[0] * 16), int(q[1] * 16)), int(r * 16), 255, -1, cv2.LINE_AA, 4)
        nail_m = None
        if nail:
            nm = np.zeros_like(m)
            nc = t - d * rt * 0.55
            cv2.ellipse(nm, (int(nc[0] * 16), int(nc[1] * 16)), (int(rt * 0.75 * 16), int(rt * 0.6 * 16)),
                        math.degrees(math.atan2(d[1], d[0])), 0, 360, 255, -1, cv2.LINE_AA, 4)
            nail_m = cv2.GaussianBlur(nm.astype(np.float32) / 255.0, (0, 0), max(0.6, rt * 0.1))
        self._shade_part(cv, buf, col, m.astype(np.float32) / 255.0, roi, min(rb, rt), skin, nail_m)

    def _ellipse_part(self, cv: _Canvas, buf: np.ndarray, col: np.ndarray, c: np.ndarray, axes: tuple[float, float],
                      ang: float, skin: np.ndarray, nail: bool, rng: np.random.Generator) -> None:
        roi = self._part_roi(cv, [c], max(axes) + 2)
        x0, y0, x1, y1 = roi
        if x1 <= x0 or y1 <= y0:
            return
        m = np.zeros((y1 - y0, x1 - x0), np.uint8)
        q = np.array(cv.px(float(c[0]), float(c[1]))) - (x0, y0)
        cv2.ellipse(m, (int(q[0] * 16), int(q[1] * 16)), (int(axes[0] * cv.k * 16), int(axes[1] * cv.k * 16)),
                    math.degrees(ang), 0, 360, 255, -1, cv2.LINE_AA, 4)
        self._shade_part(cv, buf, col, m.astype(np.float32) / 255.0, roi, min(axes) * cv.k, skin * 0.97, None)

    def _pins(self, cv: _Canvas, rng: np.random.Generator, front: np.ndarray, front_col: np.ndarray) -> None:
        """Pinned on a wall: two push pins or two bits of translucent tape at the top corners."""
        h, w = cv.alpha.shape
        pin = rng.random() < 0.5
        colour = _lin(_rand_colour(rng, 40, 230))
        for su in (-1, 1):
            u, v = su * (cv.card_w / 2 - 6), -cv.card_h / 2 + 4
            x, y = cv.px(u, v)
            m = np.zeros((h, w), np.uint8)
            if pin:
                cv2.circle(m, (int(x), int(y)), max(2, int(3.5 * cv.k)), 255, -1, cv2.LINE_AA)
                c, a = colour, 1.0
            else:
                rect = ((x, y), (14 * cv.k, 7 * cv.k), float(su * rng.uniform(30, 55)))
                cv2.fillConvexPoly(m, np.round(cv2.boxPoints(rect)).astype(np.int32), 255, cv2.LINE_AA)
                c, a = _lin((205, 225, 232)), 0.45
            bx, by, bw, bh = cv2.boundingRect(m)
            if bw == 0:
                continue
            sl = np.s_[by:by + bh, bx:bx + bw]
            mf = m[sl].astype(np.float32) / 255.0 * a
            front_col[sl] = front_col[sl] * (1 - mf[..., None]) + c * mf[..., None]
            np.maximum(front[sl], mf, out=front[sl])

    # ------------------------------------------------------------------------------------- geometry
    def _project(self, cam: _Camera, pose: _Pose, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Card-plane points (mm) to distorted frame pixels, shape (N, 2)."""
        a = u if pose.curl_axis == 0 else v
        w = pose.curl * a ** 2 / 2
        pts = pose.origin + u[:, None] * pose.ex + v[:, None] * pose.ey + w[:, None] * pose.n
        xn, yn = pts[:, 0] / pts[:, 2], pts[:, 1] / pts[:, 2]
        s = 1 + cam.k1 * (xn ** 2 + yn ** 2)
        return np.stack([cam.f * xn * s + cam.cx, cam.f * yn * s + cam.cy], axis=1)

    def _place(self, cam: _Camera, pose: _Pose, cv: _Canvas, mc: np.ndarray, rho: float) -> None:
        """Move the card so the whole mark is inside the frame (at a random place that allows it)."""
        rng = self._rng
        ang = np.linspace(0, 2 * math.pi, 24, endpoint=False)
        u, v = mc[0] + rho * np.cos(ang), mc[1] + rho * np.sin(ang)
        z = pose.origin[2]
        centre = pose.origin - (pose.origin + mc[0] * pose.ex + mc[1] * pose.ey)  # card centre relative to mark
        pts = self._project(cam, pose, u, v)
        ext = pts.max(axis=0) - pts.min(axis=0)
        lim = np.array([self.width, self.height], float)
        grow = float(np.max(ext / (lim - 10)))
        if grow > 1:  # too big to fit: step back
            z *= grow
            pose.origin[2] = z
            ext = ext / grow
        target = np.array([rng.uniform(ext[0] / 2 + 4, max(ext[0] / 2 + 5, lim[0] - ext[0] / 2 - 4)),
                           rng.uniform(ext[1] / 2 + 4, max(ext[1] / 2 + 5, lim[1] - ext[1] / 2 - 4))])
        target = 0.6 * target + 0.4 * lim / 2 if rng.random() < 0.4 else target
        mark3d = np.array([(target[0] - cam.cx) / cam.f * z, (target[1] - cam.cy) / cam.f * z, z])
        pose.origin = mark3d + centre
        for _ in range(6):
            pts = self._project(cam, pose, u, v)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            shift = np.maximum(0, 3 - lo) - np.maximum(0, hi - (lim - 3))
            if not shift.any():
                break
            pose.origin[:2] += shift / cam.f * z

    def _inverse_map(self, cam: _Camera, pose: _Pose, cv: _Canvas, roi: tuple[int, int, int, int]
                     ) -> tuple[np.ndarray, np.ndarray]:
        """For each frame pixel in roi, where its ray meets the (curled) card plane, in canvas px."""
        x0, y0, x1, y1 = roi
        xs = (np.arange(x0, x1, dtype=np.float32) - cam.cx) / cam.f
        ys = (np.arange(y0, y1, dtype=np.float32) - cam.cy) / cam.f
        xn, yn = np.meshgrid(xs, ys)
        if cam.k1:
            s = 1 + cam.k1 * (xn ** 2 + yn ** 2)
            xn, yn = xn / s, yn / s
        n, o = pose.n.astype(np.float32), pose.origin.astype(np.float32)
        ndot = n[0] * xn + n[1] * yn + n[2]
        ndot = np.where(np.abs(ndot) < 1e-4, 1e-4, ndot)
        no = float(np.dot(n, o))
        w = np.zeros_like(xn)
        u = v = xn
        for _ in range(3 if pose.curl else 1):
            t = (no + w) / ndot
            px, py, pz = t * xn - o[0], t * yn - o[1], t - o[2]
            u = pose.ex[0] * px + pose.ex[1] * py + pose.ex[2] * pz
            v = pose.ey[0] * px + pose.ey[1] * py + pose.ey[2] * pz
            a = u if pose.curl_axis == 0 else v
            w = (pose.curl * a * a / 2).astype(np.float32)
        mx = ((u + cv.card_w / 2 + cv.margin) * cv.k).astype(np.float32)
        my = ((v + cv.card_h / 2 + cv.margin) * cv.k).astype(np.float32)
        return mx, my

    def _canvas_roi(self, cam: _Camera, pose: _Pose, cv: _Canvas) -> tuple[int, int, int, int] | None:
        hw, hh = cv.card_w / 2 + cv.margin, cv.card_h / 2 + cv.margin
        t = np.linspace(-1, 1, 9)
        u = np.concatenate([t * hw, t * hw, np.full(9, -hw), np.full(9, hw)])
        v = np.concatenate([np.full(9, -hh), np.full(9, hh), t * hh, t * hh])
        pts = self._project(cam, pose, u, v)
        x0, y0 = np.floor(pts.min(axis=0)).astype(int) - 3
        x1, y1 = np.ceil(pts.max(axis=0)).astype(int) + 3
        x0, y0, x1, y1 = max(0, x0), max(0, y0), min(self.width, x1), min(self.height, y1)
        if x1 <= x0 or y1 <= y0:
            return None
        return int(x0), int(y0), int(x1), int(y1)

    def _forearm(self, img: np.ndarray, cam: _Camera, pose: _Pose, cv: _Canvas,
                 palm: tuple[np.ndarray, np.ndarray]) -> None:
        """The wrist and forearm in frame space, from the palm to beyond the frame edge."""
        rng = self._rng
        c, o = palm
        pts = self._project(cam, pose, np.array([c[0], c[0] + o[0] * 60]), np.array([c[1], c[1] + o[1] * 60]))
        d = pts[1] - pts[0]
        if np.linalg.norm(d) < 1e-3:
            return
        d = d / np.linalg.norm(d)
        d = d + np.array([0, 0.6])  # arms come from below more often than not
        d /= np.linalg.norm(d)
        width = float(np.linalg.norm(self._project(cam, pose, np.array([c[0], c[0] + 70.0]),
                                                   np.array([c[1], c[1]]))[1] - pts[0]))
        if not (np.isfinite(width) and np.all(np.isfinite(pts))) or np.abs(pts).max() > 4 * self.width:
            return  # the palm projects (nearly) behind the camera: no forearm to draw
        width = min(width, float(self.width))
        skin = tuple(int(x) for x in self._skin_srgb)
        sleeve = _rand_colour(rng, 20, 200) if rng.random() < 0.55 else skin
        start = pts[0]
        wrist = start + d * width * rng.uniform(0.3, 1.2)
        for a, b, colour in ((start, wrist, skin), (wrist, start + d * 2000, sleeve)):
            p0, p1 = tuple(int(x) for x in a), tuple(int(x) for x in b)
            thick = max(3, int(width * (0.75 if colour is skin else 0.95)))
            cv2.line(img, p0, p1, tuple(int(x * 0.8) for x in colour), thick, cv2.LINE_AA)
            cv2.line(img, p0, p1, colour, max(2, int(thick * 0.7)), cv2.LINE_AA)

    # ------------------------------------------------------------------------------------ compositing
    def _composite(self, scene: np.ndarray, cam: _Camera, pose: _Pose, cv: _Canvas, plan: _Plan,
                   light_dir: float) -> np.ndarray:
        rng = self._rng
        roi = self._canvas_roi(cam, pose, cv)
        self._warped_ink = np.zeros((self.height, self.width), np.float32)
        self._warped_hand = np.zeros((self.height, self.width), np.float32)
        if roi is None:
            return scene
        x0, y0, x1, y1 = roi
        mx, my = self._inverse_map(cam, pose, cv, roi)
        rgba = cv2.GaussianBlur(cv.rgba, (0, 0), 0.45 * cv.ratio)  # anti-alias before resampling
        warped = cv2.remap(rgba, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        masks = cv2.remap(cv.masks, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        a = warped[..., 3:4]
        sub = scene[y0:y1, x0:x1]
        if plan.setting in ("wall", "table"):  # the card's soft shadow on the surface behind it
            off = np.array([math.cos(light_dir), math.sin(light_dir)]) * rng.uniform(2, 8)
            sh = cv2.warpAffine(masks[..., 2], np.float32([[1, 0, off[0]], [0, 1, off[1]]]), (x1 - x0, y1 - y0))
            sh = cv2.GaussianBlur(sh, (0, 0), rng.uniform(2, 6))
            sub *= (1 - rng.uniform(0.2, 0.45) * sh)[..., None]
        # the card is lit by the scene's light: overall level relative to the background
        level = rng.uniform(0.8, 1.2) * max(0.55, abs(float(pose.n[2])) ** 0.3)
        scene[y0:y1, x0:x1] = sub * (1 - a) + warped[..., :3] * level * a
        self._warped_ink[y0:y1, x0:x1] = masks[..., 0]
        self._warped_hand[y0:y1, x0:x1] = masks[..., 1]
        return scene

    def _label(self, plan: _Plan, tilt: float) -> BlindLabel:
        ink = self._warped_ink > 0.5
        ys, xs = np.nonzero(ink)
        if len(xs) == 0:  # degenerate (should not happen): a 1x1 box at the centre
            box: Box = (self.width // 2, self.height // 2, 1, 1)
            return BlindLabel(plan.shape, box, 1.0, math.degrees(tilt), 0.0, False, plan.filled, plan.style)
        x0, y0, x1, y1 = int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1
        size = float(max(x1 - x0, y1 - y0))
        hand = self._warped_hand > 0.5
        near = False
        if hand.any():
            pad = int(size / 4) + 2
            bx0, by0 = max(0, x0 - pad), max(0, y0 - pad)
            bx1, by1 = min(self.width, x1 + pad), min(self.height, y1 + pad)
            h_roi = hand[by0:by1, bx0:bx1]
            if h_roi.any():
                dist = cv2.distanceTransform((~ink[by0:by1, bx0:bx1]).astype(np.uint8), cv2.DIST_L2, 3)
                near = bool(dist[h_roi].min() <= size / 4)
        return BlindLabel(plan.shape, (x0, y0, x1 - x0, y1 - y0), size, math.degrees(tilt), 0.0, near,
                          plan.filled, plan.style)

    # ----------------------------------------------------------------------------------------- camera
    def _camera(self, scene: np.ndarray, blur: float) -> np.ndarray:
        """Light colour, exposure, blur, Bayer sensor with noise, tone curve, sharpening, JPEG."""
        rng = self._rng
        if self._clean:
            return (np.clip(scene, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
        temp = rng.uniform(-1, 1)  # -1 cool daylight .. +1 warm tungsten
        tint = np.array([1 - 0.35 * max(temp, 0) + 0.1 * max(-temp, 0), 1 - 0.08 * abs(temp),
                         1 + 0.1 * max(temp, 0) - 0.12 * max(-temp, 0)], np.float32)
        awb = rng.uniform(0.5, 1.0)
        gains = tint ** (1 - awb) * np.exp(rng.normal(0, 0.05, 3)).astype(np.float32)
        r = rng.random()
        exposure = rng.uniform(0.8, 1.25) if r < 0.7 else (rng.uniform(0.45, 0.8) if r < 0.85 else rng.uniform(1.25, 1.9))
        img = scene * (gains * exposure)[None, None, :]
        if blur > 0:
            img = self._motion_blur(img, blur, rng.uniform(0, math.pi))
        if rng.random() < 0.15:
            img = cv2.GaussianBlur(img, (0, 0), rng.uniform(0.7, 2.2))
        img = self._sensor(img, rng, exposure)
        img = np.clip(img, 0, 1) ** (1 / rng.uniform(2.0, 2.4))
        contrast = rng.uniform(0.0, 0.35)
        img = img + contrast * img * (1 - img) * (2 * img - 1)  # an S-shaped tone curve
        if rng.random() < 0.45:
            sig = rng.uniform(0.8, 1.6)
            img = img + rng.uniform(0.3, 1.0) * (img - cv2.GaussianBlur(img, (0, 0), sig))
        out = (np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8)
        ok, enc = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(40, 96))])
        return cv2.imdecode(enc, cv2.IMREAD_COLOR) if ok else out

    @staticmethod
    def _motion_blur(img: np.ndarray, length: float, angle: float) -> np.ndarray:
        size = int(math.ceil(length)) | 1
        k = np.zeros((size, size), np.uint8)
        c = size // 2
        dx, dy = math.cos(angle) * length / 2, math.sin(angle) * length / 2
        cv2.line(k, (int(round((c - dx) * 16)), int(round((c - dy) * 16))),
                 (int(round((c + dx) * 16)), int(round((c + dy) * 16))), 255, 1, cv2.LINE_AA, 4)
        kf = k.astype(np.float32)
        return cv2.filter2D(img, -1, kf / kf.sum(), borderType=cv2.BORDER_REFLECT)

    def _sensor(self, img: np.ndarray, rng: np.random.Generator, exposure: float) -> np.ndarray:
        """Clip at full well, mosaic to a BGGR Bayer pattern, add shot and read noise, demosaic."""
        h, w = img.shape[:2]
        img = np.clip(img, 0, 1)
        raw = np.empty((h, w), np.float32)
        raw[0::2, 0::2] = img[0::2, 0::2, 0]
        raw[0::2, 1::2] = img[0::2, 1::2, 1]
        raw[1::2, 0::2] = img[1::2, 0::2, 1]
        raw[1::2, 1::2] = img[1::2, 1::2, 2]
        photons = rng.uniform(600, 5000) * min(1.0, exposure)
        read = rng.uniform(0.002, 0.01)
        sigma = np.sqrt(raw / photons + read ** 2)
        raw = raw + sigma * _noise_crop(self._white, rng, h, w)
        raw16 = (np.clip(raw, 0, 1) * 65535).astype(np.uint16)
        return cv2.cvtColor(raw16, cv2.COLOR_BayerRG2BGR).astype(np.float32) / 65535.0

    # ------------------------------------------------------------------------------------ backgrounds
    def _background(self, plan: _Plan) -> np.ndarray:
        rng = self._rng
        h, w = self.height, self.width
        img = np.empty((h, w, 3), np.uint8)
        scene = plan.setting
        if scene == "none":
            scene = str(rng.choice(["room", "table", "wall"], p=[0.6, 0.2, 0.2]))
        if scene == "table":
            self._table(img, rng)
        elif scene == "wall":
            self._wall_surface(img, rng)
        else:
            self._room(img, rng)
        for _ in range(int(rng.integers(2, 7))):
            self._clutter(img, rng)
        if scene == "hand" and rng.random() < 0.6:
            self._person(img, rng)
        img = cv2.GaussianBlur(img, (0, 0), rng.uniform(0.3, 2.0)) if rng.random() < 0.8 else img
        return img

    def _room(self, img: np.ndarray, rng: np.random.Generator) -> None:
        h, w = img.shape[:2]
        self._paint(img, rng, (0, 0, w, h))
        floor_y = int(rng.uniform(0.55, 0.95) * h)
        if rng.random() < 0.5:
            self._wood(img, rng, (0, floor_y, w, h))
        elif rng.random() < 0.5:
            self._tiles(img, rng, (0, floor_y, w, h))
        else:
            self._fabric(img, rng, (0, floor_y, w, h))
        items = [self._door, self._window, self._shelf, self._monitor, self._poster, self._whiteboard, self._plant]
        for i in rng.choice(len(items), size=int(rng.integers(1, 4)), replace=False):
            items[int(i)](img, rng)

    def _table(self, img: np.ndarray, rng: np.random.Generator) -> None:
        h, w = img.shape[:2]
        r = rng.random()
        if r < 0.6:
            self._wood(img, rng, (0, 0, w, h))
        elif r < 0.8:
            self._fabric(img, rng, (0, 0, w, h))
        else:
            self._tiles(img, rng, (0, 0, w, h))
        fns = [self._keyboard, self._plate, self._cable, self._paper_sheet]
        for i in rng.choice(len(fns), 2, replace=False):
            fns[int(i)](img, rng)

    def _wall_surface(self, img: np.ndarray, rng: np.random.Generator) -> None:
        h, w = img.shape[:2]
        if rng.random() < 0.35:
            self._brick(img, rng, (0, 0, w, h))
        else:
            self._paint(img, rng, (0, 0, w, h))
        fns = [self._poster, self._clock, self._whiteboard, self._paper_sheet, self._door]
        for i in rng.choice(len(fns), 2, replace=False):
            fns[int(i)](img, rng)

    def _paint(self, img: np.ndarray, rng: np.random.Generator, rect: tuple[int, int, int, int]) -> None:
        x0, y0, x1, y1 = rect
        base = np.array(_rand_colour(rng, 110, 235), np.float32)
        base = base * 0.5 + base.mean() * 0.5  # paints are mostly muted
        grad = np.linspace(rng.uniform(0.8, 1.05), rng.uniform(0.85, 1.1), y1 - y0, dtype=np.float32)[:, None, None]
        noise = 1 + 0.02 * _noise_crop(self._blotch, rng, y1 - y0, x1 - x0, 4.0)[..., None]
        img[y0:y1, x0:x1] = np.clip(base * grad * noise, 0, 255).astype(np.uint8)

    def _wood(self, img: np.ndarray, rng: np.random.Generator, rect: tuple[int, int, int, int]) -> None:
        x0, y0, x1, y1 = rect
        hh, ww = y1 - y0, x1 - x0
        if hh <= 0 or ww <= 0:
            return
        base = np.array(_jitter(rng, (60, 105, 160), 25), np.float32)
        yy, xx = np.mgrid[0:hh, 0:ww].astype(np.float32)
        a = rng.uniform(-0.2, 0.2)
        warp = 6 * _noise_crop(self._blotch, rng, hh, ww, 3.0)
        d = xx * math.sin(a) + yy * math.cos(a) + warp
        rings = 0.5 + 0.5 * np.sin(d / rng.uniform(2.0, 6.0) + 3 * _noise_crop(self._blotch, rng, hh, ww, 8.0))
        fine = _noise_crop(self._fibre, rng, hh, ww)
        tone = 0.8 + 0.2 * rings + 0.04 * fine
        img[y0:y1, x0:x1] = np.clip(base * tone[..., None], 0, 255).astype(np.uint8)
        if rng.random() < 0.5:  # planks
            step = int(rng.uniform(60, 160))
            for y in range(y0 + step, y1, step):
                cv2.line(img, (x0, y), (x1, y), tuple(int(c * 0.55) for c in base), 2)

    def _brick(self, img: np.ndarray, rng: np.random.Generator, rect: tuple[int, int, int, int]) -> None:
        x0, y0, x1, y1 = rect
        mortar = _jitter(rng, (175, 180, 185), 15)
        img[y0:y1, x0:x1] = mortar
        bh, bw = int(rng.uniform(14, 30)), 0
        bw = int(bh * rng.uniform(2.2, 3.2))
        base = np.array(_jitter(rng, (55, 75, 150), 20), float)
        for r, y in enumerate(range(y0, y1, bh)):
            off = (bw // 2) * (r % 2)
            for x in range(x0 - off, x1, bw):
                c = tuple(int(v) for v in np.clip(base * rng.uniform(0.8, 1.15), 0, 255))
                cv2.rectangle(img, (x + 2, y + 2), (x + bw - 2, y + bh - 2), c, -1)

    def _tiles(self, img: np.ndarray, rng: np.random.Generator, rect: tuple[int, int, int, int]) -> None:
        x0, y0, x1, y1 = rect
        tile = np.array(_rand_colour(rng, 120, 230), float)
        img[y0:y1, x0:x1] = _jitter(rng, (120, 120, 120), 20)
        s = int(rng.uniform(25, 70))
        for y in range(y0, y1, s):
            for x in range(x0, x1, s):
                c = tuple(int(v) for v in np.clip(tile * rng.uniform(0.93, 1.05), 0, 255))
                cv2.rectangle(img, (x + 1, y + 1), (x + s - 2, y + s - 2), c, -1)

    def _fabric(self, img: np.ndarray, rng: np.random.Generator, rect: tuple[int, int, int, int]) -> None:
        x0, y0, x1, y1 = rect
        hh, ww = y1 - y0, x1 - x0
        if hh <= 0 or ww <= 0:
            return
        c1, c2 = np.array(_rand_colour(rng, 30, 220), np.float32), np.array(_rand_colour(rng, 30, 220), np.float32)
        yy, xx = np.mgrid[0:hh, 0:ww].astype(np.float32)
        p = rng.uniform(6, 30)
        a = rng.uniform(0, math.pi)
        s1 = (np.sin((xx * math.cos(a) + yy * math.sin(a)) / p) > 0).astype(np.float32)
        if rng.random() < 0.5:  # checks
            s2 = (np.sin((-xx * math.sin(a) + yy * math.cos(a)) / p) > 0).astype(np.float32)
            s1 = 0.5 * (s1 + s2)
        weave = 1 + 0.06 * _noise_crop(self._grain, rng, hh, ww)
        out = (c1 * (1 - s1[..., None]) + c2 * s1[..., None]) * weave[..., None]
        img[y0:y1, x0:x1] = np.clip(out, 0, 255).astype(np.uint8)

    def _rect(self, rng: np.random.Generator, wmin: int, wmax: int, aspect: tuple[float, float]
              ) -> tuple[int, int, int, int]:
        w = int(rng.uniform(wmin, wmax))
        h = int(w * rng.uniform(*aspect))
        x = int(rng.uniform(-0.2 * w, self.width - 0.8 * w))
        y = int(rng.uniform(-0.2 * h, self.height - 0.8 * h))
        return x, y, x + w, y + h

    def _door(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 120, 220, (2.0, 2.6))
        c = _rand_colour(rng, 60, 230)
        cv2.rectangle(img, (x0 - 8, y0 - 8), (x1 + 8, y1), _jitter(rng, (225, 225, 225), 10), -1)
        cv2.rectangle(img, (x0, y0), (x1, y1), c, -1)
        for yy in (0.1, 0.55):
            cv2.rectangle(img, (x0 + 15, y0 + int(yy * (y1 - y0))), (x1 - 15, y0 + int((yy + 0.35) * (y1 - y0))),
                          tuple(int(v * 0.85) for v in c), 2)
        cv2.circle(img, (x1 - 18, (y0 + y1) // 2), 6, (140, 150, 160), -1, cv2.LINE_AA)

    def _window(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 150, 320, (0.7, 1.3))
        hh = max(1, y1 - y0)
        sky = np.linspace(rng.uniform(230, 255), rng.uniform(200, 250), hh)
        col = np.stack([sky, sky * rng.uniform(0.85, 0.97), sky * rng.uniform(0.7, 0.9)], axis=1)
        ys0, ys1 = max(0, y0), min(self.height, y1)
        xs0, xs1 = max(0, x0), min(self.width, x1)
        if ys1 > ys0 and xs1 > xs0:
            img[ys0:ys1, xs0:xs1] = col[ys0 - y0:ys1 - y0, None, :].astype(np.uint8)
        frame_c = _jitter(rng, (235, 235, 235), 10)
        cv2.rectangle(img, (x0, y0), (x1, y1), frame_c, 10)
        cv2.line(img, ((x0 + x1) // 2, y0), ((x0 + x1) // 2, y1), frame_c, 8)
        if rng.random() < 0.5:
            cv2.line(img, (x0, (y0 + y1) // 2), (x1, (y0 + y1) // 2), frame_c, 8)

    def _shelf(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 200, 420, (0.5, 1.0))
        wood = _jitter(rng, (70, 110, 150), 30)
        n = int(rng.integers(2, 4))
        for i in range(n):
            sy = y0 + int((i + 1) * (y1 - y0) / n)
            x = x0 + 4
            while x < x1 - 10:
                bw = int(rng.uniform(8, 24))
                bh = int(rng.uniform(0.55, 0.9) * (y1 - y0) / n)
                c = _rand_colour(rng, 20, 230)
                cv2.rectangle(img, (x, sy - bh), (x + bw, sy), c, -1)
                if bw > 12 and rng.random() < 0.5:
                    cv2.line(img, (x + bw // 2, sy - bh + 6), (x + bw // 2, sy - bh // 2), _rand_colour(rng, 150, 255),
                             1)
                x += bw + int(rng.integers(0, 3))
            cv2.rectangle(img, (x0, sy), (x1, sy + 8), wood, -1)

    def _monitor(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 160, 300, (0.56, 0.65))
        cv2.rectangle(img, (x0 - 8, y0 - 8), (x1 + 8, y1 + 8), (25, 25, 28), -1)
        screen = _rand_colour(rng, 30, 250)
        cv2.rectangle(img, (x0, y0), (x1, y1), screen, -1)
        cv2.rectangle(img, ((x0 + x1) // 2 - 10, y1 + 8), ((x0 + x1) // 2 + 10, y1 + 40), (40, 40, 40), -1)
        ink = (20, 20, 20) if sum(screen) > 380 else (230, 230, 230)
        for i in range(int(rng.integers(2, 7))):
            word = _WORDS_OX[int(rng.integers(len(_WORDS_OX)))]
            _put_text(img, rng, word, x0 + 8, y0 + 8 + i * 16, int(rng.integers(9, 13)), ink)

    def _poster(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 100, 220, (1.2, 1.5))
        paper = _rand_colour(rng, 200, 255)
        cv2.rectangle(img, (x0, y0), (x1, y1), paper, -1)
        ink = _rand_colour(rng, 0, 120)
        y = y0 + 8
        title = _WORDS_OX[int(rng.integers(len(_WORDS_OX)))]
        px = int(rng.uniform(14, 28))
        _put_text(img, rng, title, x0 + 8, y, px, ink)
        y += px + 10
        if rng.random() < 0.6:
            self._icon(img, rng, (x0 + x1) // 2, y + 35, int(rng.uniform(18, 35)), _rand_colour(rng, 0, 160))
            y += 80
        while y < y1 - 12:
            words = " ".join(_WORDS_OX[int(i)] for i in rng.integers(len(_WORDS_OX), size=3))
            _put_text(img, rng, words, x0 + 8, y, int(rng.uniform(8, 12)), ink)
            y += 16

    def _icon(self, img: np.ndarray, rng: np.random.Generator, x: int, y: int, r: int,
              colour: tuple[int, int, int]) -> None:
        """A non-mark pictogram: star, check mark, arrow, square, disc, grid or upright plus."""
        kind = int(rng.integers(7))
        t = max(2, r // 6)
        if kind == 0:
            ang = np.arange(10) * math.pi / 5 - math.pi / 2
            rr = np.where(np.arange(10) % 2 == 0, r, r * 0.42)
            pts = np.stack([x + rr * np.cos(ang), y + rr * np.sin(ang)], axis=1).astype(np.int32)
            cv2.fillPoly(img, [pts], colour, cv2.LINE_AA)
        elif kind == 1:
            pts = np.array([[x - r, y], [x - r // 3, y + r * 2 // 3], [x + r, y - r]], np.int32)
            cv2.polylines(img, [pts], False, colour, t + 1, cv2.LINE_AA)
        elif kind == 2:
            a = rng.uniform(0, 2 * math.pi)
            d = np.array([math.cos(a), math.sin(a)])
            tip = np.array([x, y]) + d * r
            cv2.line(img, tuple((np.array([x, y]) - d * r).astype(int)), tuple(tip.astype(int)), colour, t, cv2.LINE_AA)
            for s in (1, -1):
                back = tip - _rot2(s * 0.6) @ d * r * 0.5
                cv2.line(img, tuple(tip.astype(int)), tuple(back.astype(int)), colour, t, cv2.LINE_AA)
        elif kind == 3:
            cv2.rectangle(img, (x - r, y - r), (x + r, y + r), colour, t if rng.random() < 0.5 else -1)
        elif kind == 4:
            cv2.circle(img, (x, y), r, colour, -1, cv2.LINE_AA)
        elif kind == 5:
            for i in range(-2, 3):
                cv2.line(img, (x - r, y + i * r // 2), (x + r, y + i * r // 2), colour, 1)
                cv2.line(img, (x + i * r // 2, y - r), (x + i * r // 2, y + r), colour, 1)
        else:
            self._plus(img, rng, x, y, r, colour)

    def _plus(self, img: np.ndarray, rng: np.random.Generator, x: int, y: int, r: int,
              colour: tuple[int, int, int]) -> None:
        a = rng.uniform(-math.radians(18), math.radians(18))
        t = max(2, int(r * rng.uniform(0.25, 0.5)))
        if not self.plus_signs:  # a disc in its place (see __init__)
            cv2.circle(img, (x, y), max(2, int(r * 0.6)), colour, -1, cv2.LINE_AA)
            return
        for d in (np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])):
            p0, p1 = np.array([x, y]) - d * r, np.array([x, y]) + d * r
            cv2.line(img, tuple(p0.astype(int)), tuple(p1.astype(int)), colour, t, cv2.LINE_AA)

    def _whiteboard(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 220, 420, (0.55, 0.75))
        cv2.rectangle(img, (x0 - 6, y0 - 6), (x1 + 6, y1 + 6), (175, 175, 180), -1)
        cv2.rectangle(img, (x0, y0), (x1, y1), _jitter(rng, (240, 242, 242), 5), -1)
        for _ in range(int(rng.integers(2, 6))):
            colour = _INKS[("black", "blue", "red", "green")[int(rng.integers(4))]]
            r = rng.random()
            if r < 0.4:  # a scribble
                n = 30
                ang = np.cumsum(rng.normal(0, 0.5, n))
                step = rng.uniform(3, 8)
                start = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
                pts = start + np.cumsum(np.stack([np.cos(ang), np.sin(ang)], axis=1) * step, axis=0)
                cv2.polylines(img, [pts.astype(np.int32)], False, colour, 2, cv2.LINE_AA)
            elif r < 0.75:
                word = _WORDS_OX[int(rng.integers(len(_WORDS_OX)))]
                _put_text(img, rng, word, int(rng.uniform(x0, x1 - 60)), int(rng.uniform(y0, y1 - 30)),
                          int(rng.uniform(10, 26)), colour)
            else:
                self._icon(img, rng, int(rng.uniform(x0 + 20, x1 - 20)), int(rng.uniform(y0 + 20, y1 - 20)),
                           int(rng.uniform(10, 30)), colour)

    def _plant(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x = int(rng.uniform(0, self.width))
        y = int(rng.uniform(self.height * 0.4, self.height))
        pot = _rand_colour(rng, 40, 200)
        cv2.rectangle(img, (x - 25, y), (x + 25, y + 50), pot, -1)
        for _ in range(int(rng.integers(8, 20))):
            c = (int(rng.uniform(20, 70)), int(rng.uniform(90, 170)), int(rng.uniform(20, 80)))
            cx, cy = int(x + rng.normal(0, 30)), int(y - abs(rng.normal(30, 30)))
            cv2.ellipse(img, (cx, cy), (int(rng.uniform(8, 22)), int(rng.uniform(4, 9))), rng.uniform(0, 180), 0, 360,
                        c, -1, cv2.LINE_AA)

    def _keyboard(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x0, y0, x1, y1 = self._rect(rng, 260, 420, (0.3, 0.36))
        dark = rng.random() < 0.6
        body, key, ink = ((35, 35, 38), (55, 55, 60), (200, 200, 200)) if dark else \
            ((200, 200, 205), (240, 240, 242), (40, 40, 40))
        cv2.rectangle(img, (x0, y0), (x1, y1), body, -1)
        kw = (x1 - x0 - 10) / 14
        rows = 5
        kh = (y1 - y0 - 10) / rows
        letters = "QWERTYUIOPASDFGHJKLZXCVBNM"
        for r in range(rows):
            for c in range(14):
                kx, ky = int(x0 + 5 + c * kw), int(y0 + 5 + r * kh)
                cv2.rectangle(img, (kx + 1, ky + 1), (int(kx + kw - 2), int(ky + kh - 2)), key, -1)
                if kw > 14 and rng.random() < 0.7:
                    _put_text(img, rng, letters[int(rng.integers(len(letters)))], kx + 3, ky + 2,
                              max(6, int(kh * 0.35)), ink)

    def _plate(self, img: np.ndarray, rng: np.random.Generator) -> None:
        """A plate, a round mirror or a mug seen from above: rings and discs with something inside."""
        x, y = int(rng.uniform(0, self.width)), int(rng.uniform(0, self.height))
        r = int(rng.uniform(25, 90))
        rim = _rand_colour(rng, 150, 250)
        cv2.circle(img, (x, y), r, rim, -1, cv2.LINE_AA)
        cv2.circle(img, (x, y), int(r * 0.75), tuple(int(v * 0.92) for v in rim), -1, cv2.LINE_AA)
        if rng.random() < 0.7:
            for _ in range(int(rng.integers(2, 6))):  # food / a reflection
                cv2.ellipse(img, (int(x + rng.normal(0, r * 0.25)), int(y + rng.normal(0, r * 0.25))),
                            (int(r * rng.uniform(0.1, 0.3)), int(r * rng.uniform(0.08, 0.2))), rng.uniform(0, 180),
                            0, 360, _rand_colour(rng, 20, 200), -1, cv2.LINE_AA)

    def _clock(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x, y = int(rng.uniform(40, self.width - 40)), int(rng.uniform(30, self.height * 0.6))
        r = int(rng.uniform(22, 70))
        cv2.circle(img, (x, y), r, _jitter(rng, (240, 240, 240), 8), -1, cv2.LINE_AA)
        rim = _rand_colour(rng, 0, 120)
        cv2.circle(img, (x, y), r, rim, max(2, r // 8), cv2.LINE_AA)
        for i in range(12):
            a = i * math.pi / 6
            p0 = (int(x + 0.72 * r * math.cos(a)), int(y + 0.72 * r * math.sin(a)))
            p1 = (int(x + 0.84 * r * math.cos(a)), int(y + 0.84 * r * math.sin(a)))
            cv2.line(img, p0, p1, (30, 30, 30), max(1, r // 25), cv2.LINE_AA)
        for length, width in ((0.5, max(2, r // 12)), (0.75, max(1, r // 20))):
            a = rng.uniform(0, 2 * math.pi)
            cv2.line(img, (x, y), (int(x + length * r * math.cos(a)), int(y + length * r * math.sin(a))), (20, 20, 20),
                     width, cv2.LINE_AA)

    def _cable(self, img: np.ndarray, rng: np.random.Generator) -> None:
        n = 40
        ang = rng.uniform(0, 2 * math.pi) + np.cumsum(rng.normal(0, 0.12, n))
        start = np.array([rng.uniform(0, self.width), rng.uniform(0, self.height)])
        pts = start + np.cumsum(np.stack([np.cos(ang), np.sin(ang)], axis=1) * rng.uniform(8, 20), axis=0)
        c = _rand_colour(rng, 0, 80) if rng.random() < 0.7 else _rand_colour(rng, 150, 250)
        t = int(rng.uniform(3, 8))
        cv2.polylines(img, [pts.astype(np.int32)], False, c, t, cv2.LINE_AA)
        cv2.polylines(img, [pts.astype(np.int32) - 1], False, tuple(min(255, v + 50) for v in c), 1, cv2.LINE_AA)

    def _paper_sheet(self, img: np.ndarray, rng: np.random.Generator) -> None:
        """A light sheet (a printout or calendar) with text, a grid or a pictogram - never a mark."""
        x0, y0, x1, y1 = self._rect(rng, 90, 200, (1.2, 1.45))
        box = cv2.boxPoints((((x0 + x1) / 2, (y0 + y1) / 2), (x1 - x0, y1 - y0), rng.uniform(-25, 25)))
        cv2.fillConvexPoly(img, box.astype(np.int32), _jitter(rng, (240, 242, 244), 6), cv2.LINE_AA)
        ink = _rand_colour(rng, 0, 90)
        if rng.random() < 0.5:
            for i in range(int(rng.integers(3, 9))):
                words = " ".join(_WORDS_OX[int(j)] for j in rng.integers(len(_WORDS_OX), size=2))
                _put_text(img, rng, words, x0 + 10, y0 + 10 + i * 15, int(rng.uniform(8, 12)), ink)
        else:
            self._icon(img, rng, (x0 + x1) // 2, (y0 + y1) // 2, int(rng.uniform(15, 40)), ink)

    def _clutter(self, img: np.ndarray, rng: np.random.Generator) -> None:
        fns = [self._clock, self._plate, self._cable, self._paper_sheet, self._poster, self._plant]
        r = rng.random()
        if r < 0.8:
            fns[int(rng.integers(len(fns)))](img, rng)
        elif r < 0.9:
            x, y = int(rng.uniform(20, self.width - 20)), int(rng.uniform(20, self.height - 20))
            sign = _jitter(rng, (240, 240, 240), 8)
            s = int(rng.uniform(18, 45))
            cv2.rectangle(img, (x - s, y - s), (x + s, y + s), sign, -1)
            self._plus(img, rng, x, y, int(s * 0.7), _INKS["green" if rng.random() < 0.5 else "red"])
        else:
            self._face(img, rng)

    def _face(self, img: np.ndarray, rng: np.random.Generator) -> None:
        x, y = int(rng.uniform(40, self.width - 40)), int(rng.uniform(40, self.height - 40))
        r = int(rng.uniform(20, 55))
        skin = _jitter(rng, _SKINS[int(rng.integers(len(_SKINS)))], 8)
        hair = _rand_colour(rng, 10, 90)
        cv2.ellipse(img, (x, y - r // 4), (int(r * 0.85), int(r * 1.05)), 0, 0, 360, hair, -1, cv2.LINE_AA)
        cv2.ellipse(img, (x, y), (int(r * 0.75), r), 0, 0, 360, skin, -1, cv2.LINE_AA)
        for ex in (-1, 1):
            cv2.ellipse(img, (x + ex * r // 3, y - r // 6), (max(2, r // 7), max(1, r // 12)), 0, 0, 360, (40, 40, 40),
                        -1, cv2.LINE_AA)
        cv2.ellipse(img, (x, y + r // 2), (r // 4, r // 10), 0, 0, 180, (70, 70, 140), 2, cv2.LINE_AA)

    def _person(self, img: np.ndarray, rng: np.random.Generator) -> None:
        """The holder's torso (clothing, maybe striped) and sometimes their face at the top."""
        h, w = img.shape[:2]
        cx = int(rng.uniform(0.25, 0.75) * w)
        top = int(rng.uniform(0.25, 0.6) * h)
        half = int(rng.uniform(0.25, 0.45) * w)
        x0, x1 = max(0, cx - half), min(w, cx + half)
        if rng.random() < 0.5:
            self._fabric(img, rng, (x0, top, x1, h))
        else:
            img[top:h, x0:x1] = _rand_colour(rng, 15, 230)
        if rng.random() < 0.4 and top > 60:
            r = min(top // 2, int(rng.uniform(35, 70)))
            skin = _jitter(rng, _SKINS[int(rng.integers(len(_SKINS)))], 8)
            cv2.ellipse(img, (cx, top - r), (int(r * 0.75), r), 0, 0, 360, skin, -1, cv2.LINE_AA)
            for ex in (-1, 1):
                cv2.circle(img, (cx + ex * r // 3, top - r - r // 6), max(2, r // 9), (35, 35, 35), -1, cv2.LINE_AA)
