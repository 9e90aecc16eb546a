"""A second, independent frame generator for held-out evaluation (never used for tuning).

It differs from `synthetic.py` in how frames are made, not only in its seed:

- drawing: Pillow (RGBA layers, TrueType glyphs, rounded strokes, hand-drawn jittered strokes) and
  a perspective warp of the whole rendered card layer by Pillow's `Image.transform`, where
  `synthetic.py` draws with OpenCV primitives and warps with `cv2.warpPerspective`;
- backgrounds: scikit-image sample images that the tuning generator never uses (cat, colorwheel,
  horse, logo, retina, stereo motorcycle, cell, checkerboard, Shepp-Logan phantom, binary blobs,
  microaneurysms), or a procedural room of wall, shelf and window;
- cards: other proportions (square to 1.6:1, rounded corners, off-centre marks) and much narrower
  borders next to the mark (0.04 to 0.35 of the mark's size, versus about 0.35 to 0.65);
- marks: TrueType glyphs (DejaVu Sans/Serif Bold, `FONT_FILES`; Pillow's bundled font as well),
  hand-drawn strokes, rounded caps; filled triangles as well as outlines; X bars at 60 to 120 degrees;
- ink: black, blue, red, green, brown, purple markers;
- a hand: two to four fingers and a thumb as skin-coloured capsules over the card's edges and corners,
  often close to the mark;
- conditions: tilt to 45 degrees about a random axis, motion blur to 20 px plus defocus, lighting by
  vignette, gradient and colour cast, exposure gain 0.3 to 1.6 (clipped highlights), shot noise,
  JPEG quality 40 to 90 through Pillow's encoder;
- clutter: TrueType words full of O and X (EXIT, BOX, OXO, TOXIC...), prohibition signs, squares,
  discs, filled triangles off any card, a cat's face, cables, textures, and decoy cards with words,
  discs or squares.

- optics (off by default, `lens`): a wide-angle lens in OpenCV's radial model (k1 = -lens, focal length the
  frame's width), applied to the composed scene before the sensor's light, blur, noise and JPEG; the
  tuning generator's lens is its own model, applied by its own code.

`HeldOutGenerator(seed).frame(shape)` returns a BGR uint8 frame and a `HeldOutLabel` (or None).
`HeldOutGenerator(seed).clip(shape)` returns a `HeldOutClip`: 36 frames at 30 fps of one such scene seen by a
camera that stands or sways as a walking robot's head does, the card held up from frame 6 on
(`bench/vision_clips.py`); with `hand`, `rolling_shutter` and `auto_exposure`, what a person and a real camera add:
the card raised into view by an unsteady hand, rows read out over 10-30 ms, a gain that follows the brightness.
"""

from __future__ import annotations

import io
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFilter, ImageFont

from schemas.messages import Shape

Box = tuple[int, int, int, int]
Rng = np.random.Generator

HELDOUT_BACKGROUNDS: tuple[str, ...] = (
    "cat",
    "colorwheel",
    "horse",
    "logo",
    "retina",
    "stereo_motorcycle",
    "cell",
    "checkerboard",
    "shepp_logan_phantom",
    "binary_blobs",
    "microaneurysms",
)
FONT_FILES: tuple[str, ...] = (
    "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf",
    "/usr/share/fonts/truetype/dejavu/DejaVuSerif-Bold.ttf",
    "/usr/share/fonts/truetype/dejavu/DejaVuSansCondensed-Bold.ttf",
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
)
"""The fonts a seed's frames are drawn with (Debian's fonts-dejavu-core and fonts-dejavu-extra): which of them are
installed changes every draw after the first glyph, so a machine without one draws other frames from the same seed
(`missing_fonts`; the bench says so). LiberationSans-Bold was listed too until stop 46, but no machine that measured
a figure had it (seed 1616 reproduced to the frame without it): a desktop with it drew other frames."""
INKS: tuple[tuple[int, int, int], ...] = (  # RGB
    (15, 15, 20),
    (40, 40, 45),
    (20, 40, 150),
    (190, 25, 30),
    (20, 120, 45),
    (90, 50, 25),
    (90, 30, 120),
)
SKIN: tuple[tuple[int, int, int], ...] = ((235, 195, 170), (210, 160, 125), (170, 120, 85), (110, 75, 55))
WORDS: tuple[str, ...] = (
    "EXIT",
    "BOX",
    "OXO",
    "TOXIC",
    "ZOO",
    "NO",
    "XO",
    "OX",
    "ROBOT",
    "STOP",
    "OPEN",
    "FOX",
    "MAX 20",
    "ONE WAY",
    "XEROX",
    "MOTOR",
    "TAXI",
    "oxygen",
    "look",
    "box 0",
)


@dataclass(frozen=True)
class HeldOutLabel:
    shape: Shape
    box: Box
    size: float  # the mark's longest side in the frame, pixels
    tilt_deg: float  # out-of-plane tilt of the card
    blur_px: float  # motion blur length
    finger_near: bool  # a finger within a quarter of the mark's size of it
    filled: bool  # a filled triangle


@dataclass(frozen=True)
class Drawn:
    """One thing a held-out frame shows besides its background, for telling what a false mark was made of
    (`bench/vision_bench.py`'s false marks by what they lie on): its kind (`_clutter`'s kinds, or the held card's:
    "mark card", "blank card", "decoy disc", "decoy square", "decoy outline square", "decoy word") and its box in
    the frame (x, y, w, h; where a lens bends the scene, the box before it); a cable's curve as well, with its width."""

    kind: str
    box: Box
    curve: np.ndarray | None = None
    width: float = 0.0


CLIP_FPS = 30.0
CLIP_FRAMES = 36
CLIP_SHOWN = 6
"""Frames of a clip before the card is held up: the confirmation windows start from the scene without it."""
CLIP_ZOOM = 1.1
LAYER_PAD = 64
"""Pixels a held card's own layer reaches past the frame on every side (`HeldOutGenerator._held_card`)."""
_PAD_SHIFT = np.array([[1, 0, -LAYER_PAD], [0, 1, -LAYER_PAD], [0, 0, 1.0]])
"""A card layer's pixels -> the scene's."""


@dataclass(frozen=True)
class HeldOutClip:
    frames: list[np.ndarray]
    boxes: list[Box | None]
    """The mark's box in each frame; None before the card is held up, or while less than half of it is in view."""
    label: HeldOutLabel | None
    """The mark as drawn in the scene (its box before the camera's view; blur 0); None for a mark-free clip."""
    shown: int
    """The first frame with the card."""
    walking: bool
    """Whether the camera sways as on a walking robot (else it stands still: only the noise changes)."""
    sway_px: float
    """The camera's sway or bob amplitude, whichever is larger, pixels."""
    blur_px: float
    """The longest motion streak of the mark over one exposure in the clip, pixels (with a hand: while in view)."""
    in_view: int | None = None
    """The first frame with the mark's box (more than half of it in view); None for a mark-free clip."""


def _fonts() -> list[Path]:
    return [Path(f) for f in FONT_FILES if Path(f).is_file()]


def missing_fonts() -> list[str]:
    """The font files of `FONT_FILES` this machine lacks (frames then differ from the READMEs' for the same seed)."""
    return [f for f in FONT_FILES if not Path(f).is_file()]


def _font(path: Path | None, size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    if path is None:
        return ImageFont.load_default(size=size)
    return ImageFont.truetype(str(path), size)


class HeldOutGenerator:
    """Deterministic for a given seed."""

    def __init__(self, seed: int = 0, width: int = 640, height: int = 480, lens: float = 0.0) -> None:
        self.rng = np.random.default_rng(seed)
        self.width, self.height = width, height
        named = _load_bank()
        self.bank = [img for _, img in named]
        self.bank_names = [name for name, _ in named]
        self.drawn: list[Drawn] = []
        """What the last scene showed over its background, in the order drawn (`Drawn`); it draws no random number"""
        self.background = ""
        """The last scene's background: a `HELDOUT_BACKGROUNDS` name, or "room"."""
        self.fonts: list[Path | None] = [*_fonts(), None]
        # `lens`: the barrel distortion of the camera's lens (OpenCV's k1 = -lens); 0: a pinhole camera. It draws
        # no random numbers, so a seed's scenes are the same with and without it.
        self._lens_maps = lens_maps(lens, width, height) if lens else None
        # a clip's hand and shutter draw from a stream of their own, so the scenes are the same without them
        self._clip_rng = np.random.default_rng([seed, 1])

    # ------------------------------------------------------------------ public
    def frame(self, shape: Shape | None) -> tuple[np.ndarray, HeldOutLabel | None]:
        rng = self.rng
        bg, _, label = self._scene(shape)
        blur = float(rng.uniform(0, 20)) if rng.random() < 0.7 else 0.0
        if self._lens_maps is not None:
            bg = Image.fromarray(
                cv2.remap(np.asarray(bg), *self._lens_maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            )
        img = self._camera(bg, blur)
        if label is not None:
            label = HeldOutLabel(
                label.shape, label.box, label.size, label.tilt_deg, blur, label.finger_near, label.filled
            )
        return img, label

    def clip(
        self,
        shape: Shape | None,
        frames: int = CLIP_FRAMES,
        shown: int = CLIP_SHOWN,
        *,
        hand: bool = False,
        rolling_shutter: bool = False,
        auto_exposure: bool = False,
    ) -> HeldOutClip:
        """`frames` frames at `CLIP_FPS` of one scene seen by a camera on a walking robot (three clips in four; the
        rest stand still), the card held up from frame `shown` on (before it, the same scene without the card).

        The camera: its view is the scene enlarged by `CLIP_ZOOM` (so its sway stays inside the scene). Walking, it
        sways sideways (0-18 px) and rolls (0-3 degrees) once a stride of 0.9-1.4 s, bobs (0-8 px) twice a stride,
        is jolted at each footfall (a 10 Hz shake of 0-12 px dying away in about 0.1 s) and closes in on the scene
        by up to 12 % a second. Each frame is exposed for the clip's 4-33 ms, and the mark's travel in that time
        is its motion blur (a clip's longest: p50 2.5 px, p90 7 px, at most 12 px over 1,600 clips). The light,
        focus, noise level and JPEG quality are the clip's (drawn as for a frame); the noise is new in every frame.

        Off by default, what a person and a real camera add (`_Hand`, `_Shutter`; their random numbers come from a
        stream of their own, so a seed's scenes, cameras and noise are the same with them and without):
        - `hand`: the card does not appear at frame `shown`: a hand starts raising it then, from below the view,
          turned, and brings it to its place at a peak speed of 0.5-2 m/s (a minimum-jerk reach of 0.2-0.8 s),
          then holds it with a slow drift, a tremor and a wobble. The card's own travel in the exposure blurs the
          card and its fingers.
        - `rolling_shutter`: the rows are read out top to bottom over 10-30 ms, so each band of 8 rows sees the
          scene, the camera and the hand at its own time (what moves is sheared).
        - `auto_exposure`: the camera's gain follows the frame's mean brightness back to what it metered on the
          first frame, with a time constant of 0.15-0.6 s: a bright card brought up darkens the next frames."""
        if self._lens_maps is not None:
            raise ValueError("clips are made through a pinhole camera: no lens")
        rng, w, h = self.rng, self.width, self.height
        layers: list[np.ndarray] = []
        scene, empty, label = self._scene(shape, keep_empty=True, layers=layers if hand else None)
        look = self._look()
        noise, quality = float(rng.uniform(0, 0.6)), int(rng.integers(40, 91))
        walking = rng.random() < 0.75
        stride = float(rng.uniform(0.9, 1.4))
        sway, bob, jolt, roll = (float(rng.uniform(0, a)) for a in (18.0, 8.0, 12.0, 3.0))
        approach = float(rng.uniform(0, 0.12))
        phase = rng.uniform(0, 2 * math.pi, 2)
        exposure = float(rng.uniform(0.004, 0.033))
        if not walking:
            sway = bob = jolt = roll = approach = 0.0
        person = _Hand.draw(self._clip_rng, layers[0] if layers else None, h)
        shutter = _Shutter.draw(self._clip_rng, rolling_shutter, auto_exposure)

        def view(t: float) -> np.ndarray:  # scene pixels -> frame pixels at time t
            a = 2 * math.pi * t / stride + phase[0]
            z = CLIP_ZOOM * (1 + approach * t)
            r = math.radians(roll * math.sin(a))
            since = (a % math.pi) / math.pi * stride / 2  # seconds since the last footfall (two a stride)
            shake = jolt * math.exp(-since / 0.06) * math.sin(2 * math.pi * 10 * since)
            shift = (w / 2 + sway * math.sin(a), h / 2 + bob * math.sin(2 * a + phase[1]) + shake)
            turn = np.array(
                [[z * math.cos(r), -z * math.sin(r), 0], [z * math.sin(r), z * math.cos(r), 0], [0, 0, 1]]
            )
            return (
                np.array([[1, 0, shift[0]], [0, 1, shift[1]], [0, 0, 1]])
                @ turn
                @ np.array([[1, 0, -w / 2], [0, 1, -h / 2], [0, 0, 1.0]])
            )

        t_up = shown / CLIP_FPS

        def mark_view(t: float) -> np.ndarray:  # the mark's scene pixels -> frame pixels at time t
            return view(t) @ person.at(t - t_up) if person is not None else view(t)

        x, y, bw, bh = label.box if label is not None else (w // 2, h // 2, 0, 0)
        corners = np.array([[x, y], [x + bw, y], [x + bw, y + bh], [x, y + bh]], np.float64)
        centre = corners.mean(axis=0, keepdims=True)
        card = None if person is None else _premultiplied(layers[0])
        out: list[np.ndarray] = []
        boxes: list[Box | None] = []
        streaks: list[float] = []
        gain, metered = 1.0, None
        for i in range(frames):
            t = i / CLIP_FPS
            raised = card is not None and i >= shown
            t_mark = shutter.row_time(t, float(_project(mark_view(t), centre)[0, 1]), h)
            box = (
                _in_view(_project(mark_view(t_mark), corners), w, h)
                if label is not None and i >= shown
                else None
            )
            camera_streak = _streak(view, t_mark, exposure, centre)
            src = np.asarray(scene if i >= shown and person is None or empty is None else empty)
            seen = shutter.warp(src, view, t, cv2.BORDER_REFLECT_101)
            if raised:
                assert card is not None and person is not None
                card_streak = _streak(mark_view, t_mark, exposure, centre)
                held = shutter.warp(
                    card,
                    lambda tb: view(tb) @ person.at(tb - t_up) @ _PAD_SHIFT,
                    t,
                    cv2.BORDER_CONSTANT,
                )
                back = seen.astype(np.float32)
                if camera_streak[0] >= 1.5:
                    back = _motion_blur(back, *camera_streak)
                if card_streak[0] >= 1.5:
                    held = _motion_blur(held, *card_streak)
                alpha = held[..., 3:]
                seen = np.clip(back * (1 - alpha) + held[..., :3], 0, 255).round().astype(np.uint8)
            arr = _lit(Image.fromarray(seen), look, gain)
            if shutter.ae_rate:
                level = float(arr.mean())
                metered = level if metered is None else metered
                gain = float(np.clip(gain * (metered / max(level, 1.0)) ** shutter.ae_rate, 0.25, 4.0))
            if not raised and camera_streak[0] >= 1.5:
                arr = _motion_blur(arr, *camera_streak)
            if person is None or box is not None:
                streaks.append(card_streak[0] if raised else camera_streak[0])
            out.append(self._sensor(arr, noise, quality))
            boxes.append(box)
        return HeldOutClip(
            out,
            boxes,
            label,
            shown,
            walking,
            max(sway, bob),
            max(streaks, default=0.0),
            in_view=next((i for i, b in enumerate(boxes) if b is not None), None),
        )

    # ------------------------------------------------------------------ scene
    def _scene(
        self, shape: Shape | None, keep_empty: bool = False, layers: list[np.ndarray] | None = None
    ) -> tuple[Image.Image, Image.Image | None, HeldOutLabel | None]:
        """Background, clutter and the held card (or, mark-free, a blank or decoy card half the time): the scene,
        the same scene before the card was put in it (with `keep_empty`, else None), and the mark's label. With
        `layers`, the card and its fingers are appended to it as a layer of their own (`_held_card`)."""
        rng = self.rng
        self.drawn = []
        bg = self._background()
        for _ in range(int(rng.integers(2, 7))):
            self._clutter(bg)
        empty = bg.copy() if keep_empty else None
        label = None
        if shape is not None:
            label = self._held_card(bg, shape, layers)
        elif rng.random() < 0.5:
            self._held_card(bg, None, layers)  # a blank or decoy card held up
        return bg, empty, label

    def _background(self) -> Image.Image:
        rng, w, h = self.rng, self.width, self.height
        if self.bank and rng.random() < 0.75:
            pick = int(rng.integers(len(self.bank)))
            src, self.background = self.bank[pick], self.bank_names[pick]
            scale = max(w / src.width, h / src.height) * float(rng.uniform(1.0, 1.8))
            big = src.resize((math.ceil(src.width * scale), math.ceil(src.height * scale)), Image.BILINEAR)
            x0 = int(rng.integers(0, big.width - w + 1))
            y0 = int(rng.integers(0, big.height - h + 1))
            img = big.crop((x0, y0, x0 + w, y0 + h))
            if rng.random() < 0.5:
                img = img.transpose(Image.FLIP_TOP_BOTTOM)
            return img.convert("RGB")
        # a room: a wall colour, a shelf, a window, a door frame
        self.background = "room"
        wall = tuple(int(v) for v in rng.integers(60, 200, 3))
        img = Image.new("RGB", (w, h), wall)  # type: ignore[arg-type]
        d = ImageDraw.Draw(img)
        for _ in range(int(rng.integers(2, 6))):
            x, y = int(rng.integers(-50, w)), int(rng.integers(-50, h))
            col = tuple(int(v) for v in rng.integers(20, 240, 3))
            d.rectangle((x, y, x + int(rng.integers(40, 300)), y + int(rng.integers(10, 250))), fill=col)  # type: ignore[arg-type]
        return img

    def _clutter(self, img: Image.Image) -> None:
        rng, w, h = self.rng, self.width, self.height
        d = ImageDraw.Draw(img)
        kind = ["words", "sign", "square", "disc", "triangle", "face", "cable", "texture"][
            int(rng.integers(8))
        ]
        cx, cy = float(rng.uniform(0, w)), float(rng.uniform(0, h))
        s = float(math.exp(rng.uniform(math.log(25), math.log(220))))
        col = _ink(rng) if rng.random() < 0.6 else tuple(int(v) for v in rng.integers(0, 256, 3))
        if kind == "words":
            font = _font(self.fonts[int(rng.integers(len(self.fonts)))], max(10, int(s / 2)))
            text = " ".join(rng.choice(WORDS, size=int(rng.integers(1, 4))))
            if rng.random() < 0.5:  # on a light sign panel
                tb = d.textbbox((cx, cy), text, font=font)
                pad = 0.3 * (tb[3] - tb[1])
                d.rectangle((tb[0] - pad, tb[1] - pad, tb[2] + pad, tb[3] + pad), fill=_paper(rng))
            d.text((cx, cy), text, fill=col, font=font)
            self._note("words", d.textbbox((cx, cy), text, font=font))
        elif kind == "sign":  # a prohibition sign: red ring and bar on white
            r = s / 2
            d.ellipse(
                (cx - r, cy - r, cx + r, cy + r),
                fill=(240, 240, 235),
                outline=(200, 20, 20),
                width=max(2, int(0.15 * s)),
            )
            a = math.radians(45)
            d.line(
                (cx - r * math.cos(a), cy - r * math.sin(a), cx + r * math.cos(a), cy + r * math.sin(a)),
                fill=(200, 20, 20),
                width=max(2, int(0.12 * s)),
            )
            self._note(kind, (cx - r, cy - r, cx + r, cy + r))
        elif kind == "square":
            pts = _poly(cx, cy, s / 2, 4, float(rng.uniform(0, 90)))
            if rng.random() < 0.5:
                d.polygon(pts, fill=col)
            else:
                d.line([*pts, pts[0]], fill=col, width=max(2, int(s * rng.uniform(0.06, 0.2))), joint="curve")
            self._note(kind, (cx - s / 2, cy - s / 2, cx + s / 2, cy + s / 2))
        elif kind == "disc":
            d.ellipse((cx - s / 2, cy - s / 2, cx + s / 2, cy + s / 2), fill=col)
            self._note(kind, (cx - s / 2, cy - s / 2, cx + s / 2, cy + s / 2))
        elif kind == "triangle":  # filled, off any card: clutter
            d.polygon(_poly(cx, cy, s / 2, 3, float(rng.uniform(0, 120))), fill=col)
            self._note(kind, (cx - s / 2, cy - s / 2, cx + s / 2, cy + s / 2))
        elif kind == "face" and self.bank:
            cat = self.bank[0]  # the cat's face
            face = cat.crop((110, 20, 300, 210)).resize((max(8, int(s * 1.3)),) * 2)
            img.paste(face, (int(cx), int(cy)))
            self._note(kind, (cx, cy, cx + face.width, cy + face.height))
        elif kind == "cable":
            p = rng.uniform([-60, -60], [w + 60, h + 60], size=(4, 2))
            t = np.linspace(0, 1, 50)[:, None]
            c = (1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t**2 * p[2] + t**3 * p[3]
            width = int(rng.integers(2, 14))
            d.line([tuple(q) for q in c], fill=col, width=width, joint="curve")
            self._note(kind, (*c.min(axis=0), *c.max(axis=0)), curve=c, width=width)
        else:  # texture: a patch of a held-out texture image
            src = self.bank[int(rng.integers(len(self.bank)))] if self.bank else None
            if src is not None:
                patch = src.resize((max(8, int(s * 1.5)),) * 2).convert("RGB")
                img.paste(patch, (int(cx), int(cy)))
                self._note("texture", (cx, cy, cx + patch.width, cy + patch.height))

    def _note(self, kind: str, corners: tuple[float, ...], curve: np.ndarray | None = None, width: float = 0.0) -> None:
        """Record a thing just drawn (`Drawn`), given its box's corners (x0, y0, x1, y1) in the frame."""
        x0, y0, x1, y1 = (int(round(v)) for v in corners)
        self.drawn.append(Drawn(kind, (x0, y0, x1 - x0 + 1, y1 - y0 + 1), curve, width))

    def _held_card(
        self, img: Image.Image, shape: Shape | None, layers: list[np.ndarray] | None = None
    ) -> HeldOutLabel | None:
        """Render a card (with the mark, or a decoy) and the fingers holding it on a padded RGBA
        canvas at 2x, warp it into the frame, and return the mark's label. With `layers`, the card is also
        appended to it alone: an RGBA array of the frame with `LAYER_PAD` pixels more on every side (so a hand
        can move a card cut by the frame's edge), drawing no random number."""
        rng = self.rng
        size = float(math.exp(rng.uniform(math.log(40), math.log(400))))  # mark size in the frame
        k = 3.0 if size < 90 else 2.0 if size < 200 else 1.0  # supersampling
        ms = size * k
        borders = rng.uniform(0.04, 0.35, size=4) * ms  # left, top, right, bottom
        mark_w = ms * (float(rng.uniform(0.85, 1.0)) if shape is Shape.O else 1.0)
        card_w = mark_w + borders[0] + borders[2]
        card_h = ms + borders[1] + borders[3]
        aspect = float(rng.uniform(1.0, 1.6))  # stretch the longer way, sometimes
        if card_w < card_h * aspect and rng.random() < 0.5:
            extra = card_h * aspect - card_w
            borders[0] += extra * rng.uniform(0, 1)
            card_w = card_h * aspect
            borders[2] = card_w - mark_w - borders[0]
        pad = 0.6 * max(card_w, card_h)
        cw, ch = int(card_w + 2 * pad), int(card_h + 2 * pad)
        canvas = Image.new("RGBA", (cw, ch), (0, 0, 0, 0))
        mask = Image.new("L", (cw, ch), 0)
        d = ImageDraw.Draw(canvas)
        paper = _paper(rng)
        radius = float(rng.uniform(0, 0.12)) * min(card_w, card_h)
        card_box = (pad, pad, pad + card_w, pad + card_h)
        d.rounded_rectangle(card_box, radius=radius, fill=(*paper, 255))
        mx0, my0 = pad + borders[0], pad + borders[1]
        mark_box = (mx0, my0, mx0 + mark_w, my0 + ms)
        filled = False
        held = "mark card" if shape is not None else "blank card"
        if shape is not None:
            ink = _ink(rng)
            filled = self._draw_mark(canvas, mask, shape, mark_box, ink)
        elif rng.random() < 0.6:
            held = self._decoy(canvas, mark_box)
        finger_near = self._fingers(canvas, card_box, mark_box)
        # the pose: in-plane rotation, tilt about a random axis, a position that keeps the card in view
        rot = float(rng.uniform(-180, 180))
        tilt = float(rng.uniform(0, 45))
        axis = float(rng.uniform(0, 2 * math.pi))
        ccx, ccy = pad + card_w / 2, pad + card_h / 2
        mcx, mcy = (mark_box[0] + mark_box[2]) / 2, (mark_box[1] + mark_box[3]) / 2
        for _ in range(40):
            target = (float(rng.uniform(0, self.width)), float(rng.uniform(0, self.height)))
            hm = _homography(ccx, ccy, 1.0 / k, rot, tilt, axis, target)
            mc = _project(
                hm,
                np.array(
                    [
                        [mark_box[0], mark_box[1]],
                        [mark_box[2], mark_box[1]],
                        [mark_box[2], mark_box[3]],
                        [mark_box[0], mark_box[3]],
                    ]
                ),
            )
            if mc.min() >= 3 and mc[:, 0].max() <= self.width - 3 and mc[:, 1].max() <= self.height - 3:
                break
            if shape is None:
                break
        else:
            # the mark cannot fit: shrink it into the middle of the frame
            hm = _homography(ccx, ccy, 0.6 / k, rot, tilt, axis, (self.width / 2, self.height / 2))
            hm = hm @ np.array([[1, 0, ccx - mcx], [0, 1, ccy - mcy], [0, 0, 1.0]])
        inv = np.linalg.inv(hm)
        inv /= inv[2, 2]
        coeffs = tuple(float(v) for v in inv.reshape(-1)[:8])
        warped = canvas.transform((self.width, self.height), Image.PERSPECTIVE, coeffs, Image.BICUBIC)
        img.paste(warped, (0, 0), warped)
        corners = _project(hm, np.array([[card_box[0], card_box[1]], [card_box[2], card_box[1]],
                                         [card_box[2], card_box[3]], [card_box[0], card_box[3]]]))
        self._note(held, (*corners.min(axis=0), *corners.max(axis=0)))
        if layers is not None:
            shifted = inv @ _PAD_SHIFT
            shifted /= shifted[2, 2]
            size = (self.width + 2 * LAYER_PAD, self.height + 2 * LAYER_PAD)
            layers.append(
                np.asarray(
                    canvas.transform(
                        size,
                        Image.PERSPECTIVE,
                        tuple(float(v) for v in shifted.reshape(-1)[:8]),
                        Image.BICUBIC,
                    )
                )
            )
        if shape is None:
            return None
        wm = np.asarray(mask.transform((self.width, self.height), Image.PERSPECTIVE, coeffs, Image.BILINEAR))
        if self._lens_maps is not None:  # the ink where the lens shows it, as `frame` shows the scene
            wm = cv2.remap(wm, *self._lens_maps, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        ys, xs = np.nonzero(wm > 127)
        if len(xs) == 0:
            return None
        box = (int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1))
        return HeldOutLabel(shape, box, float(max(box[2], box[3])), tilt, 0.0, finger_near, filled)

    def _draw_mark(
        self,
        canvas: Image.Image,
        mask: Image.Image,
        shape: Shape,
        box: tuple[float, ...],
        ink: tuple[int, ...],
    ) -> bool:
        rng = self.rng
        x0, y0, x1, y1 = box
        w, h = x1 - x0, y1 - y0
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        stroke = max(2, int(float(rng.uniform(0.08, 0.2)) * min(w, h)))
        layer = Image.new("L", canvas.size, 0)
        d = ImageDraw.Draw(layer)
        style = int(rng.integers(3))  # 0 geometric, 1 font glyph, 2 hand-drawn
        filled = False
        if shape is Shape.X and style == 1 and self.fonts:
            self._glyph(d, "X", box)
        elif shape is Shape.X:
            half = float(rng.uniform(60, 120)) / 2
            base = 90.0
            r = min(w, h) / 2 - stroke / 2
            for a in (base - half, base + half):
                dx, dy = r * math.cos(math.radians(a)) * 1.3, r * math.sin(math.radians(a))
                dx = max(-r, min(r, dx))
                pts = [(cx - dx, cy - dy), (cx + dx, cy + dy)]
                if style == 2:
                    pts = _jitter(rng, pts, 0.04 * min(w, h))
                d.line(pts, fill=255, width=stroke, joint="curve")
                if rng.random() < 0.5:  # round caps
                    for px, py in (pts[0], pts[-1]):
                        d.ellipse(
                            (px - stroke / 2, py - stroke / 2, px + stroke / 2, py + stroke / 2), fill=255
                        )
        elif shape is Shape.O and style == 1 and self.fonts:
            self._glyph(d, "O", box)
        elif shape is Shape.O:
            if style == 2:
                t = np.linspace(0, 2 * math.pi, 60)
                wob = 1 + 0.03 * np.sin(3 * t + rng.uniform(0, 6))
                pts = [
                    (
                        cx + (w / 2 - stroke / 2) * wb * math.cos(a),
                        cy + (h / 2 - stroke / 2) * wb * math.sin(a),
                    )
                    for a, wb in zip(t, wob, strict=True)
                ]
                d.line(pts, fill=255, width=stroke, joint="curve")
            else:
                d.ellipse(box, outline=255, width=stroke)
        else:
            verts = [(cx, y0), (x1, y1), (x0, y1)]
            if rng.random() < 0.35:
                d.polygon(verts, fill=255)
                filled = True
            else:
                inset = _inset(verts, stroke)
                if style == 2:
                    verts = _jitter(rng, verts, 0.03 * min(w, h))
                    inset = _jitter(rng, inset, 0.02 * min(w, h))
                d.polygon(verts, fill=255)
                d.polygon(inset, fill=0)
        ink_img = Image.new("RGBA", canvas.size, (*ink, 255))
        canvas.paste(ink_img, (0, 0), layer)
        mask.paste(255, (0, 0), layer.point(lambda v: 255 if v > 127 else 0))
        return filled

    def _glyph(self, d: ImageDraw.ImageDraw, char: str, box: tuple[float, ...]) -> None:
        rng = self.rng
        x0, y0, x1, y1 = box
        path = self.fonts[int(rng.integers(len(self.fonts)))]
        probe = _font(path, 200)
        tb = d.textbbox((0, 0), char, font=probe)
        scale = min((x1 - x0) / (tb[2] - tb[0]), (y1 - y0) / (tb[3] - tb[1]))
        font = _font(path, max(8, int(200 * scale)))
        tb = d.textbbox((0, 0), char, font=font)
        ox = (x0 + x1) / 2 - (tb[0] + tb[2]) / 2
        oy = (y0 + y1) / 2 - (tb[1] + tb[3]) / 2
        d.text((ox, oy), char, fill=255, font=font)

    def _decoy(self, canvas: Image.Image, box: tuple[float, ...]) -> str:
        """Draw a decoy on a mark-free card, in `box`; its kind (`Drawn`)."""
        rng = self.rng
        d = ImageDraw.Draw(canvas)
        x0, y0, x1, y1 = box
        ink = (*_ink(rng), 255)
        what = int(rng.integers(4))
        s = min(x1 - x0, y1 - y0)
        if what == 0:
            d.ellipse(box, fill=ink)
            return "decoy disc"
        if what == 1:
            d.rectangle(box, outline=ink, width=max(2, int(0.12 * s)))
            return "decoy outline square"
        if what == 2:
            d.rectangle(box, fill=ink)
            return "decoy square"
        word = str(rng.choice(WORDS))
        font = _font(self.fonts[int(rng.integers(len(self.fonts)))], max(8, int(s / max(2, len(word)) * 1.4)))
        d.text((x0, (y0 + y1) / 2), word, fill=ink, font=font, anchor="lm")
        return "decoy word"

    def _fingers(self, canvas: Image.Image, card: tuple[float, ...], mark: tuple[float, ...]) -> bool:
        """Two to four fingers over one edge and a thumb over the opposite one, each a capsule that
        stops short of the mark. True if a finger tip ends within a quarter of the mark's size of it."""
        rng = self.rng
        if rng.random() < 0.25:
            return False
        d = ImageDraw.Draw(canvas)
        skin = SKIN[int(rng.integers(len(SKIN)))]
        shade = tuple(int(0.7 * v) for v in skin)
        cx0, cy0, cx1, cy1 = card
        mx0, my0, mx1, my1 = mark
        msize = max(mx1 - mx0, my1 - my0)
        width = max(6.0, float(rng.uniform(0.09, 0.16)) * max(cx1 - cx0, cy1 - cy0))
        near = False
        side = int(rng.integers(4))
        for edge, count in ((side, int(rng.integers(2, 5))), ((side + 2) % 4, 1)):
            along = float(rng.uniform(0.1, 0.7))
            for f in range(count):
                t = along + f * 1.05 * width / max(cx1 - cx0, cy1 - cy0)
                if t > 1:
                    break
                # start outside the card, point inward, end short of the mark
                if edge == 0:
                    sx, sy, dx, dy, room = cx0 - 3 * width, cy0 + t * (cy1 - cy0), 1, 0, mx0 - cx0
                elif edge == 1:
                    sx, sy, dx, dy, room = cx0 + t * (cx1 - cx0), cy0 - 3 * width, 0, 1, my0 - cy0
                elif edge == 2:
                    sx, sy, dx, dy, room = cx1 + 3 * width, cy0 + t * (cy1 - cy0), -1, 0, cx1 - mx1
                else:
                    sx, sy, dx, dy, room = cx0 + t * (cx1 - cx0), cy1 + 3 * width, 0, -1, cy1 - my1
                in_line = (dx == 0 and mx0 - width / 2 < sx < mx1 + width / 2) or (
                    dy == 0 and my0 - width / 2 < sy < my1 + width / 2
                )
                gap = float(rng.uniform(0.02, 0.3)) * msize
                reach = (
                    max(0.3 * width, room - gap) if in_line else float(rng.uniform(0.3, 1.0)) * room + width
                )
                length = 3 * width + reach
                ex, ey = sx + dx * length, sy + dy * length
                d.line((sx, sy, ex, ey), fill=(*shade, 255), width=int(width) + 2)
                d.ellipse(
                    (ex - width / 2 - 1, ey - width / 2 - 1, ex + width / 2 + 1, ey + width / 2 + 1),
                    fill=(*shade, 255),
                )
                d.line((sx, sy, ex, ey), fill=(*skin, 255), width=int(width))
                d.ellipse((ex - width / 2, ey - width / 2, ex + width / 2, ey + width / 2), fill=(*skin, 255))
                if in_line and room - reach < 0.25 * msize + width / 2:
                    near = True
        return near

    # ------------------------------------------------------------------ the camera
    def _camera(self, img: Image.Image, blur: float) -> np.ndarray:
        look = self._look()
        arr = _lit(img, look)
        if blur >= 1.5:
            arr = _motion_blur(arr, blur, float(self.rng.uniform(0, math.pi)))
        return self._sensor(arr, float(self.rng.uniform(0, 0.6)))

    def _look(self) -> _Look:
        """The light on a frame (exposure, colour cast, vignette, a strong gradient) and the lens's focus."""
        rng, w, h = self.rng, self.width, self.height
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        gain = float(rng.uniform(0.3, 1.6))
        cast = rng.uniform(0.85, 1.15, 3).astype(np.float32)
        r2 = ((xx - w / 2) / (w / 2)) ** 2 + ((yy - h / 2) / (h / 2)) ** 2
        vignette = 1 - float(rng.uniform(0, 0.45)) * r2 / 2
        ang = float(rng.uniform(0, 2 * math.pi))
        grad = 1 + float(rng.uniform(0, 0.7)) * (
            (xx / w - 0.5) * math.cos(ang) + (yy / h - 0.5) * math.sin(ang)
        )
        light = (gain * vignette * grad)[..., None] * cast
        defocus = float(rng.uniform(0.3, 1.8)) if rng.random() < 0.4 else 0.0
        return _Look(light, defocus)

    def _sensor(self, arr: np.ndarray, noise: float, quality: int | None = None) -> np.ndarray:
        """Shot noise (its variance grows with the signal, `noise` x it) and JPEG at `quality` (None: drawn after
        the noise, 40-90) -> the BGR frame."""
        rng = self.rng
        arr = arr + rng.standard_normal(arr.shape).astype(np.float32) * np.sqrt(noise * arr + 1.0)
        out = Image.fromarray(np.clip(arr, 0, 255).astype(np.uint8))
        buf = io.BytesIO()
        out.save(buf, format="JPEG", quality=int(rng.integers(40, 91)) if quality is None else quality)
        buf.seek(0)
        rgb = np.asarray(Image.open(buf).convert("RGB"))
        return np.ascontiguousarray(rgb[:, :, ::-1])


@dataclass(frozen=True)
class _Look:
    light: np.ndarray
    """(h, w, 3) factors: exposure x vignette x gradient x colour cast"""
    defocus: float
    """Gaussian blur radius of an out-of-focus lens; 0: in focus"""


def _lit(img: Image.Image, look: _Look, gain: float = 1.0) -> np.ndarray:
    """The scene's pixels under the light, times `gain` (a camera's automatic exposure), clipped; then focus."""
    a = np.asarray(img, np.float32) * look.light
    a = np.clip(a * np.float32(gain) if gain != 1.0 else a, 0, 255)
    out = Image.fromarray(a.astype(np.uint8))
    if look.defocus:
        out = out.filter(ImageFilter.GaussianBlur(look.defocus))
    return np.asarray(out, np.float32)


def _premultiplied(layer: np.ndarray) -> np.ndarray:
    """An RGBA uint8 layer -> float32 colour times coverage (0-255) and coverage (0-1), ready to warp and blur."""
    alpha = layer[..., 3:].astype(np.float32) / 255
    return np.concatenate([layer[..., :3].astype(np.float32) * alpha, alpha], axis=2)


def _streak(
    to_frame: Callable[[float], np.ndarray], t: float, exposure: float, at: np.ndarray
) -> tuple[float, float]:
    """The travel of the scene point `at` in the frame over an exposure centred on `t`: its length and angle."""
    dx, dy = (_project(to_frame(t + exposure / 2), at) - _project(to_frame(t - exposure / 2), at))[0]
    return math.hypot(dx, dy), math.atan2(dy, dx)


HELD_SIZE_M = 0.25
"""What a hand holds up, card and fingers, measured along its longest side: the scale of a hand's reach."""


@dataclass(frozen=True)
class _Hand:
    """A hand raising a held card into view and holding it: scene pixels -> scene pixels at a time since it
    started. The reach is a minimum-jerk move (how people's arms move) from below the view at a peak speed of
    0.5-2 m/s (its length in metres from the card's size in pixels, `HELD_SIZE_M`; taking 0.2-0.8 s), the card
    turned by `turn` degrees and straightened on the way; held, it drifts (0-12 px, 0.2-0.8 Hz), trembles
    (0.3-2.5 px, 8-12 Hz: physiological tremor) and wobbles (0-4 degrees)."""

    centre: tuple[float, float]
    start: tuple[float, float]
    rise_s: float
    turn: float
    drift: tuple[float, float, float, float, float]  # amplitude x, y (px), frequency (Hz), phases
    tremor: tuple[float, float, float, float]  # amplitude (px), frequency (Hz), phases
    wobble: tuple[float, float, float]  # amplitude (degrees), frequency (Hz), phase

    @classmethod
    def draw(cls, rng: np.random.Generator, layer: np.ndarray | None, height: int) -> _Hand | None:
        """A hand for the card on `layer` (None: no card held up, no hand). Draws the same numbers either way."""
        speed = float(rng.uniform(0.5, 2.0))
        way, turn = math.radians(rng.uniform(-35, 35)), float(rng.uniform(-15, 15))
        drift = (
            *(float(v) for v in rng.uniform(0, 12, 2)),
            float(rng.uniform(0.2, 0.8)),
            *(float(v) for v in rng.uniform(0, 2 * math.pi, 2)),
        )
        tremor = (
            float(rng.uniform(0.3, 2.5)),
            float(rng.uniform(8, 12)),
            *(float(v) for v in rng.uniform(0, 2 * math.pi, 2)),
        )
        wobble = (float(rng.uniform(0, 4)), float(rng.uniform(0.3, 1.0)), float(rng.uniform(0, 2 * math.pi)))
        if layer is None:
            return None
        ys, xs = np.nonzero(layer[..., 3] > 0)
        x0, x1, y0, y1 = (float(v) - LAYER_PAD for v in (xs.min(), xs.max(), ys.min(), ys.max()))
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        # from below, far enough that the whole card, turned any way, starts out of the scene
        reach = (height - cy + math.hypot(x1 - x0, y1 - y0) / 2 + 10) / math.cos(way)
        per_m = max(x1 - x0, y1 - y0) / HELD_SIZE_M
        # a minimum-jerk move's peak speed is 1.875 times its mean
        rise = min(max(1.875 * reach / per_m / speed, 0.2), 0.8)
        start = (reach * math.sin(way), reach * math.cos(way))
        return cls((cx, cy), start, rise, turn, drift, tremor, wobble)  # type: ignore[arg-type]

    def at(self, t: float) -> np.ndarray:
        """Where the hand has the card `t` seconds after it started raising it (before: still out of view)."""
        s = min(max(t / self.rise_s, 0.0), 1.0)
        left = 1 - (10 * s**3 - 15 * s**4 + 6 * s**5)  # of the reach still to go
        ax, ay, f, p, q = self.drift
        ta, tf, tp, tq = self.tremor
        dx = (
            left * self.start[0]
            + ax * math.sin(2 * math.pi * f * t + p)
            + ta * math.sin(2 * math.pi * tf * t + tp)
        )
        dy = (
            left * self.start[1]
            + ay * math.sin(2 * math.pi * f * t + q)
            + ta * math.sin(2 * math.pi * tf * t + tq)
        )
        r = math.radians(
            left * self.turn + self.wobble[0] * math.sin(2 * math.pi * self.wobble[1] * t + self.wobble[2])
        )
        cx, cy = self.centre
        back = np.array([[1, 0, -cx], [0, 1, -cy], [0, 0, 1.0]])
        turn = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1.0]])
        return np.array([[1, 0, cx + dx], [0, 1, cy + dy], [0, 0, 1.0]]) @ turn @ back


@dataclass(frozen=True)
class _Shutter:
    """How the clip's camera reads out and exposes: a global shutter (`readout_s` 0) or a rolling one reading the
    rows top to bottom in `readout_s`, in bands of `BAND` rows; and its automatic exposure (`ae_rate`, the share
    of the metering error corrected per frame; 0: a fixed gain)."""

    readout_s: float
    ae_rate: float
    BAND = 8

    @classmethod
    def draw(cls, rng: np.random.Generator, rolling: bool, auto_exposure: bool) -> _Shutter:
        readout, tau = float(rng.uniform(0.010, 0.030)), float(rng.uniform(0.15, 0.6))
        return cls(readout if rolling else 0.0, 1 - math.exp(-1 / (CLIP_FPS * tau)) if auto_exposure else 0.0)

    def row_time(self, t: float, y: float, height: int) -> float:
        return t + self.readout_s * min(max(y, 0.0), height) / height if self.readout_s else t

    def warp(
        self, src: np.ndarray, to_frame: Callable[[float], np.ndarray], t: float, border: int
    ) -> np.ndarray:
        """`src` seen in the frame at time `t`; each band of rows at its own time when the shutter rolls."""
        h, w = src.shape[0], src.shape[1]
        if src.shape[2] == 4:  # a card layer: the frame's size
            h, w = h - 2 * LAYER_PAD, w - 2 * LAYER_PAD
        if not self.readout_s:
            return cv2.warpPerspective(src, to_frame(t), (w, h), flags=cv2.INTER_LINEAR, borderMode=border)
        bands = []
        for y0 in range(0, h, self.BAND):
            y1 = min(y0 + self.BAND, h)
            m = np.array([[1, 0, 0], [0, 1, -y0], [0, 0, 1.0]]) @ to_frame(self.row_time(t, (y0 + y1) / 2, h))
            bands.append(cv2.warpPerspective(src, m, (w, y1 - y0), flags=cv2.INTER_LINEAR, borderMode=border))
        return np.concatenate(bands, axis=0)


def _motion_blur(arr: np.ndarray, length: float, angle: float) -> np.ndarray:
    """A straight streak `length` pixels long at `angle` (radians from the x axis)."""
    n = math.ceil(length) | 1
    kernel = np.zeros((n, n), np.float32)
    c = n // 2
    for s in np.linspace(-length / 2, length / 2, 4 * n):
        kernel[round(c + s * math.sin(angle)), round(c + s * math.cos(angle))] += 1
    kernel /= kernel.sum()
    return cv2.filter2D(arr, -1, kernel, borderType=cv2.BORDER_REFLECT)


# ---------------------------------------------------------------------- helpers
def max_lens(width: int, height: int) -> float:
    """The strongest lens the one-coefficient model can show this frame through: with k1 = -k the model's
    distorted radius r (1 - k r^2) peaks at (2/3) / sqrt(3 k), and the frame's corners must lie inside it."""
    corner = math.hypot(width / 2, height / 2) / width  # normalised by the focal length, the frame's width
    return (2 / 3) ** 2 / 3 / corner**2


def lens_camera(lens: float, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """The held-out lens in OpenCV's model: (camera matrix, distortion coefficients k1, k2, p1, p2). ValueError
    for a lens stronger than `max_lens` (no scene point would show at the frame's corners)."""
    if not 0 <= lens < max_lens(width, height):
        raise ValueError(
            f"lens {lens}: between 0 and {max_lens(width, height):.3f} for a {width}x{height} frame "
            "(a stronger barrel lens folds the frame's corners back in this one-coefficient model)"
        )
    k = np.array([[width, 0, width / 2], [0, width, height / 2], [0, 0, 1]], np.float64)
    return k, np.array([-lens, 0, 0, 0], np.float64)


def lens_maps(lens: float, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """`cv2.remap` maps that show a pinhole frame through the lens: for each pixel of the distorted frame, where
    the pinhole frame has it (`cv2.undistortPoints` of that pixel, back into pixels)."""
    k, dist = lens_camera(lens, width, height)
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    pts = np.stack([xx.ravel(), yy.ravel()], axis=1).reshape(-1, 1, 2)
    src = cv2.undistortPoints(pts, k, dist, P=k).reshape(height, width, 2)
    return np.ascontiguousarray(src[..., 0]), np.ascontiguousarray(src[..., 1])


def _load_bank() -> list[tuple[str, Image.Image]]:
    """The background images of `HELDOUT_BACKGROUNDS` that scikit-image has, with their names."""
    try:
        from skimage import data
    except ImportError:
        return []
    bank: list[tuple[str, Image.Image]] = []
    for name in HELDOUT_BACKGROUNDS:
        try:
            # binary_blobs draws new blobs on every call unless given a seed: the set must repeat
            a = np.asarray(data.binary_blobs(rng=0) if name == "binary_blobs" else getattr(data, name)())
        except (AttributeError, OSError, ValueError, ImportError):
            continue
        if a.dtype == bool:
            a = np.where(a, 200, 60).astype(np.uint8)
        elif a.dtype != np.uint8:
            a = (255 * (a - a.min()) / max(1e-9, float(a.max() - a.min()))).astype(np.uint8)
        if a.ndim == 3 and a.shape[2] == 4:
            a = a[:, :, :3]
        bank.append((name, Image.fromarray(a).convert("RGB")))
    return bank


def _ink(rng: Rng) -> tuple[int, int, int]:
    base = np.array(INKS[int(rng.integers(len(INKS)))], np.int64)
    return tuple(int(v) for v in np.clip(base + rng.integers(-12, 13, 3), 0, 255))  # type: ignore[return-value]


def _paper(rng: Rng) -> tuple[int, int, int]:
    tints = ((250, 250, 248), (245, 240, 222), (232, 232, 232), (250, 246, 205), (228, 236, 246))
    base = np.array(tints[int(rng.integers(len(tints)))], np.int64)
    return tuple(int(v) for v in np.clip(base + rng.integers(-10, 6, 3), 0, 255))  # type: ignore[return-value]


def _poly(cx: float, cy: float, r: float, n: int, rot: float) -> list[tuple[float, float]]:
    return [
        (
            cx + r * math.cos(math.radians(rot + 360 * i / n)),
            cy + r * math.sin(math.radians(rot + 360 * i / n)),
        )
        for i in range(n)
    ]


def _jitter(rng: Rng, pts: list[tuple[float, float]], amount: float) -> list[tuple[float, float]]:
    """A hand-drawn stroke: the segments subdivided, each point nudged."""
    out: list[tuple[float, float]] = []
    closed = len(pts) > 2
    seq = [*pts, pts[0]] if closed else pts
    for (ax, ay), (bx, by) in itertools.pairwise(seq):
        for t in np.linspace(0, 1, 6, endpoint=False):
            out.append(
                (
                    ax + t * (bx - ax) + rng.normal(0, amount / 3),
                    ay + t * (by - ay) + rng.normal(0, amount / 3),
                )
            )
    if not closed:
        out.append(seq[-1])
    return out


def _inset(verts: list[tuple[float, float]], stroke: float) -> list[tuple[float, float]]:
    """The polygon shrunk towards its centroid so that its edges move in by `stroke`."""
    p = np.array(verts, np.float64)
    c = p.mean(axis=0)
    (ux, uy), (vx, vy) = p[1] - p[0], p[2] - p[0]
    area = 0.5 * abs(ux * vy - uy * vx) if len(p) == 3 else 0.0
    perim = float(np.sum(np.hypot(*(np.roll(p, -1, axis=0) - p).T)))
    inr = 2 * area / perim if perim else 1.0
    f = max(0.05, (inr - stroke) / inr)
    return [tuple(v) for v in c + (p - c) * f]  # type: ignore[misc]


def _homography(
    cx: float,
    cy: float,
    scale: float,
    rot: float,
    tilt: float,
    axis: float,
    target: tuple[float, float],
    focal: float = 650.0,
) -> np.ndarray:
    """Canvas pixels -> frame pixels: centre, scale, rotate in plane, tilt about an in-plane axis at
    angle `axis` (Rodrigues), project with a pinhole of focal length `focal`."""
    t = np.array([[1, 0, -cx], [0, 1, -cy], [0, 0, 1.0]])
    r = math.radians(rot)
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1.0]])
    k = np.array([math.cos(axis), math.sin(axis), 0.0])
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    a = math.radians(tilt)
    rt = np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx
    rot3 = rt @ rz
    # plane point (u, v) -> 3-D (scale*u, scale*v, 0) rotated, then at depth focal
    m = np.column_stack([rot3[:, 0] * scale, rot3[:, 1] * scale, [0, 0, focal]])
    proj = np.array([[focal, 0, target[0]], [0, focal, target[1]], [0, 0, 1.0]])
    return proj @ m @ t


def _project(h: np.ndarray, pts: np.ndarray) -> np.ndarray:
    p = np.column_stack([pts, np.ones(len(pts))]) @ h.T
    return p[:, :2] / p[:, 2:3]


def _in_view(corners: np.ndarray, w: int, h: int) -> Box | None:
    """The box around four projected corners, cut to the frame; None if less than half of it is in view."""
    x0, y0 = corners.min(axis=0)
    x1, y1 = corners.max(axis=0)
    cx0, cy0, cx1, cy1 = max(x0, 0.0), max(y0, 0.0), min(x1, w - 1.0), min(y1, h - 1.0)
    if cx1 <= cx0 or cy1 <= cy0 or (cx1 - cx0) * (cy1 - cy0) < 0.5 * (x1 - x0) * (y1 - y0):
        return None
    return (round(cx0), round(cy0), round(cx1 - cx0) + 1, round(cy1 - cy0) + 1)
