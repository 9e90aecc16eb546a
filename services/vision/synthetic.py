"""Synthetic camera frames: X, O and triangle marks on hand-held cards in front of cluttered scenes.

Each frame is labelled (the mark's shape and its box in pixels), so the generator serves the tests,
the benchmark and the `synthetic:` source of the service. Variations: rotation, perspective tilt,
scale (a small card across the room to one filling the frame), uneven lighting, motion blur, sensor
noise, JPEG artefacts, and distractors (squares, discs, letters and text, faces, cables, textures,
and cards that carry a non-mark). Backgrounds come from scikit-image's bundled sample images when
scikit-image is importable, otherwise they are procedural.
"""

from __future__ import annotations

import functools
import itertools
import math
import string
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import cv2
import numpy as np

from schemas.messages import Shape
from services.runtime import get_logger

if TYPE_CHECKING:
    from services.vision.calibration import Calibration

log = get_logger("vision.synthetic")

Box = tuple[int, int, int, int]
Rng = np.random.Generator

SKIMAGE_BACKGROUNDS: tuple[str, ...] = (
    "astronaut",
    "brick",
    "camera",
    # not "chelsea": it is the held-out generator's "cat" under another name
    "coffee",
    "coins",
    "grass",
    "gravel",
    "moon",
    "page",
    "text",
    "rocket",
    "clock",
    "hubble_deep_field",
    "immunohistochemistry",
)
DISTRACTORS: tuple[str, ...] = (
    "square",
    "disc",
    "text",
    "face",
    "cable",
    "texture",
    "card",
    "filled_triangle",
    "sign",
)
EXTRA_DISTRACTORS: tuple[str, ...] = ("arrow", "star", "check", "clock", "crossing")
"""Clutter kinds the generator can draw but does not by default (`Variation.kinds`): adding one to the
defaults would change every seed's frames. "arrow" (round vision21): an arrow, its head a filled
triangle, on a light label or straight on the scene; the verifier trained before it named 58 % of such
labels a triangle (`docs/experiments/scripts/vision21_triclutter_probe.py`). "star", "check" and "clock"
(round vision23): a star sticker or printed star, a check mark (a tick, sometimes in its box) and a clock
face (a ring with ticks and two hands inside), each on a light plate or straight on the scene: everyday
things the third, blind generator (`blind.py`) showed the detector taking for an X, a triangle or an O.
"crossing" (round vision45): two cables or pen strokes crossing at the clutter's point, or one cable lying in a
loop that crosses itself there, each running on well past the crossing; stop 78 found the detector's proposer
naming such crossings X (`docs/experiments/scripts/vision44_crossing_probe.py`, its own drawing code)."""


@dataclass(frozen=True)
class Label:
    """Ground truth of one mark in a frame."""

    shape: Shape
    box: Box


@dataclass(frozen=True)
class Variation:
    """Ranges the generator samples from. Narrow one to test a single variation."""

    size: tuple[float, float] = (26.0, 380.0)  # mark width in pixels, sampled log-uniformly
    rotation_deg: float = 180.0  # in-plane rotation, uniform in +-this
    tilt_deg: float = 50.0  # out-of-plane tilt, uniform in 0..this
    light: float = 0.6  # uneven lighting strength, 0 (flat) .. 1 (strong gradient and shadow)
    dim: tuple[float, float] = (0.35, 1.4)  # overall exposure gain (above 1 the paper clips)
    blur: float = 20.0  # longest motion blur, pixels
    noise: float = 10.0  # largest Gaussian sensor-noise sigma, grey levels
    jpeg: tuple[int, int] = (40, 95)  # JPEG quality range (0 disables)
    distractors: tuple[int, int] = (2, 7)  # how many clutter objects
    kinds: tuple[str, ...] = DISTRACTORS
    border: tuple[float, float] = (0.03, 0.6)  # card border beside the mark, fraction of its width
    stroke: tuple[float, float] = (0.11, 0.19)  # stroke width range, fraction of the mark's width
    colour_ink: float = 0.35  # share of marks in red, blue or green ink instead of dark grey
    filled_triangle: float = 0.25  # share of triangle marks drawn filled
    fingers: float = 0.4  # share of cards with fingers reaching towards the mark
    finger_over: float = 0.3  # share of those whose fingertips lie over the mark's edge
    pale_ink: float = 0.2  # share of marks in pale ink (mixed 15-45 % towards the paper)
    hand_drawn: float = 0.0
    """share of marks drawn by hand with a pen (`_draw_by_hand`): a triangle of uneven sides and angles, an X of
    bowed bars of unequal length crossing off their middles, an O a wobbly oval whose stroke overlaps where it
    closes; every stroke wavers, swells and thins, with round ends and corners (0: the generator's exact shapes)"""
    hand_drawn_shapes: tuple[Shape, ...] = (Shape.X, Shape.O, Shape.TRIANGLE)  # the shapes `hand_drawn` applies to
    hand_variety: float = 0.0
    """share of cards with fingers whose fingers vary as people's do: any skin tone (dark brown, as dark
    as some inks, to pale), 0.12-0.45 of the mark's width wide (a finger beside a small mark is wide),
    over any of the card's four edges (0: light skin, 0.2 wide, over the bottom edge)"""
    sheen: float = 0.0
    """share of cards that are glossy, with a lamp's reflection on them over the mark (`Sheen`, round vision66; 0: matte
    cards, no draw at all)"""
    sheen_shapes: tuple[Shape, ...] = (Shape.X, Shape.O, Shape.TRIANGLE)
    """the marks whose cards `sheen` makes glossy (round vision67: X and TRIANGLE, the danger marks); the draw is made
    for every card, so that a scene's other draws do not depend on it"""
    lens: float = 0.0
    """the camera lens's barrel distortion, the same for every frame (0: a pinhole camera). It draws
    nothing, so the scenes are those of the same seed without it, only seen through the lens. It is k
    in r_scene = r (1 + k r^2) / (1 + k r_corner^2), r measured from the frame's centre in half-widths:
    the corners stay the corners, the middle is magnified and straight lines near the edges bow (at a
    640 px wide frame's side edges, the scene's point at mid-height appears 13 px further out with 0.1
    and 27 px with 0.3, while the corners stay put)."""

    def only(self, **changes: object) -> Variation:
        return replace(self, **changes)  # type: ignore[arg-type]


MILD = Variation(
    size=(60.0, 160.0),
    rotation_deg=0.0,
    tilt_deg=0.0,
    light=0.0,
    dim=(1.0, 1.0),
    blur=0.0,
    noise=2.0,
    jpeg=(0, 0),
    distractors=(0, 0),
    border=(0.35, 0.65),
    colour_ink=0.0,
    filled_triangle=0.0,
    fingers=0.0,
    finger_over=0.0,
    pale_ink=0.0,
)
"""A clean scene: one variation at a time is added to this in the tests."""


@dataclass(frozen=True)
class Sheen:
    """A lamp's reflection on a glossy card (`Variation.sheen`), in the card's own frame: the reflection of a tube or a
    window, a stadium (a segment of `length` widened by `radius` each side) of light added to the card in linear light
    (gamma 2.2), flat at `peak` (the paper's white: 1) inside and falling to 0 over `soft` beyond its edge (smoothstep),
    at `offset` from the mark's centre, turned by `angle`. Lengths are in mark widths. It is drawn on the printed card
    before the fingers (they are above the gloss) and before the camera's light, blur, noise and JPEG; the bench's
    highlight (`bench/glare.py`, a Gaussian lobe added to the finished frame) is made otherwise on purpose."""

    offset: tuple[float, float]
    length: float
    radius: float
    soft: float
    angle: float
    peak: float

    @classmethod
    def draw(cls, rng: Rng) -> Sheen:
        """Over the mark: its centre within 0.4 mark widths of the mark's, 0-1.5 long, 0.03-0.25 wide each side with
        an edge of 0.03-0.3, its peak 0.15-1.2 of white (a fifth wash the ink out at their middle)."""
        return cls(
            offset=(float(rng.uniform(-0.4, 0.4)), float(rng.uniform(-0.4, 0.4))),
            length=float(rng.uniform(0.0, 1.5)),
            radius=float(rng.uniform(0.03, 0.25)),
            soft=float(rng.uniform(0.03, 0.3)),
            angle=float(rng.uniform(0, math.pi)),
            peak=float(rng.uniform(0.15, 1.2)),
        )

    def light(self, shape: tuple[int, int], centre: tuple[float, float], mark: float) -> np.ndarray:
        """The light it adds to each pixel of a card of `shape` (rows, columns) whose mark, `mark` pixels wide, is
        centred at `centre` (x, y): float32, linear, the paper's white 1."""
        ys, xs = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float32)
        c, s = math.cos(self.angle), math.sin(self.angle)
        dx = (xs - centre[0]) / mark - self.offset[0]
        dy = (ys - centre[1]) / mark - self.offset[1]
        along = np.clip(c * dx + s * dy, -self.length / 2, self.length / 2)
        dist = np.hypot(dx - along * c, dy - along * s)  # from the segment
        t = np.clip((self.radius + self.soft - dist) / self.soft, 0.0, 1.0)
        return (self.peak * t * t * (3 - 2 * t)).astype(np.float32)


def _add_light(img: np.ndarray, light: np.ndarray) -> np.ndarray:
    """`img` (uint8 BGR) with `light` (per pixel, linear, white 1) added in linear light (gamma 2.2), clipped."""
    linear = (img.astype(np.float32) / 255.0) ** 2.2 + light[..., None]
    return np.round(np.clip(linear, 0.0, 1.0) ** (1 / 2.2) * 255.0).astype(np.uint8)


@dataclass
class Scene:
    """One sampled scene: everything but the sensor noise is fixed, so a held card stays put."""

    background: np.ndarray  # BGR, distractors drawn, before lighting
    shape: Shape | None
    size: float
    stroke: float  # stroke width as a fraction of the mark width
    rotation_deg: float
    tilt: tuple[float, float]  # degrees about x and y
    center: tuple[float, float]
    card: tuple[float, float]  # card width and height as multiples of the mark width
    paper: tuple[int, int, int]
    ink: tuple[int, int, int]
    light: np.ndarray  # float32 gain, HxW
    blur: tuple[float, float]  # motion blur length (px) and angle (deg)
    noise: float
    jpeg: int
    skew: float = 0.0  # hand-drawn irregularity: X arm angle offset (deg)
    hand: bool = True
    filled: bool = False  # a filled triangle
    fingers: int = 0  # fingers reaching from a card edge towards the mark
    finger_gap: float = 0.2  # how far short of the mark they stop, fraction of its width (< 0: over it)
    finger_width: float = 0.2  # fraction of the mark's width
    skin: tuple[int, int, int] = (95, 125, 175)  # BGR; the lit middle of a finger is 25 levels lighter
    finger_edge: int = 0  # the card edge they come over: quarter turns from the bottom
    lens: float = 0.0  # barrel distortion k (`Variation.lens`), applied before light, blur, noise and JPEG
    by_hand: int | None = None  # the random stream of a mark drawn by hand (`Variation.hand_drawn`), or None
    sheen: Sheen | None = None  # a lamp's reflection on a glossy card (`Variation.sheen`), or None


@dataclass(frozen=True)
class Painted:
    """One thing a recording generator (`SceneGenerator.record`) drew over the background: its kind (a `DISTRACTORS`
    name, a decoy card's "decoy ...", or "mark card") and the pixels it changed."""

    kind: str
    mask: np.ndarray  # bool, height x width


class SceneGenerator:
    """Renders labelled frames. Deterministic for a given seed."""

    def __init__(
        self,
        width: int = 640,
        height: int = 480,
        seed: int = 0,
        variation: Variation = Variation(),
        use_skimage: bool = True,
        backgrounds: tuple[str, ...] = SKIMAGE_BACKGROUNDS,
    ) -> None:
        self.width = width
        self.height = height
        self.variation = variation
        self.rng = np.random.default_rng(seed)
        named = _load_backgrounds(backgrounds) if use_skimage else []
        self.bank = [img for _, img in named]
        self.bank_names = [name for name, _ in named]
        self.face = _load_face() if use_skimage else None
        self.record = False
        """Record what each scene draws (`painted`, `card`, `background`): a bench's tuning split does, to tell what
        each false mark lies on. It draws no random number, so a seed's frames are the same either way."""
        self.painted: list[Painted] = []
        """The last scene's clutter, in the order drawn (with `record`)."""
        self.card: Painted | None = None
        """The held card of the last frame rendered, drawn over the clutter (with `record`; None without a mark, or
        through a lens)."""
        self.background = ""
        """The last scene's background: a scikit-image sample's name, or "procedural"."""

    # ------------------------------------------------------------------ public
    def frame(self, shape: Shape | None) -> tuple[np.ndarray, list[Label]]:
        """A fresh random scene holding `shape` (or nothing), rendered once."""
        return self.render(self.scene(shape))

    def scene(self, shape: Shape | None) -> Scene:
        v, rng = self.variation, self.rng
        size = float(math.exp(rng.uniform(math.log(v.size[0]), math.log(v.size[1]))))
        size = min(size, 0.9 * min(self.width, self.height))
        card = (1 + 2 * rng.uniform(*v.border), 1 + 2 * rng.uniform(*v.border))
        tilt_mag = rng.uniform(0, v.tilt_deg)
        tilt_dir = rng.uniform(0, 2 * math.pi)
        rotation = float(rng.uniform(-v.rotation_deg, v.rotation_deg))
        tilt = (tilt_mag * math.cos(tilt_dir), tilt_mag * math.sin(tilt_dir))
        (cx, cy), size = self._place(size, rotation, tilt)
        paper_level = int(rng.integers(205, 256))
        tint = rng.integers(-12, 6, size=3)
        scene = Scene(
            background=self._background(),
            shape=shape,
            size=size,
            stroke=float(rng.uniform(*v.stroke)),
            rotation_deg=rotation,
            tilt=tilt,
            center=(cx, cy),
            card=card,
            paper=tuple(int(np.clip(paper_level + t, 0, 255)) for t in tint),  # type: ignore[arg-type]
            ink=_mark_ink(rng, v.colour_ink),
            light=self._lighting(v.light),
            blur=(float(rng.uniform(0, v.blur)), float(rng.uniform(0, 180))),
            noise=float(rng.uniform(0, v.noise)),
            jpeg=int(rng.integers(v.jpeg[0], v.jpeg[1] + 1)) if v.jpeg[1] > 0 else 0,
            skew=float(rng.uniform(-10, 10)),
            hand=bool(rng.random() < 0.6),
            filled=bool(rng.random() < v.filled_triangle),
            fingers=int(rng.integers(1, 4)) if rng.random() < v.fingers else 0,
            finger_gap=float(rng.uniform(0.03, 0.3)),
        )
        # drawn last, so that the draws above (and the scenes of older seeds) stay as they were
        if rng.random() < v.finger_over:
            scene.finger_gap = -float(rng.uniform(0.0, 0.3))  # the tips cover the mark's edge
        if rng.random() < v.pale_ink:
            mix = float(rng.uniform(0.15, 0.45))
            scene.ink = tuple(  # type: ignore[assignment]
                int(i + mix * (p - i)) for i, p in zip(scene.ink, scene.paper, strict=True)
            )
        # no draw at all when hand_variety is 0, so that older seeds' scenes stay as they were
        if scene.fingers and v.hand_variety and rng.random() < v.hand_variety:
            scene.finger_width = float(rng.uniform(0.12, 0.45))
            scene.skin = _skin(rng)
            scene.finger_edge = int(rng.integers(0, 4))
        # no draw at all when hand_drawn is 0, so that older seeds' scenes stay as they were
        if v.hand_drawn and rng.random() < v.hand_drawn:
            by_hand = int(rng.integers(2**31))
            scene.by_hand = by_hand if shape in v.hand_drawn_shapes else None
        # no draw at all when sheen is 0, so that older seeds' scenes stay as they were
        if v.sheen and rng.random() < v.sheen:
            sheen = Sheen.draw(rng)
            scene.sheen = sheen if shape in v.sheen_shapes else None
        scene.lens = v.lens  # the camera's, not drawn
        return scene

    def _place(
        self, size: float, rotation: float, tilt: tuple[float, float]
    ) -> tuple[tuple[float, float], float]:
        """A card centre that keeps the whole mark inside the frame; shrinks a mark that cannot fit."""
        for attempt in range(60):
            if attempt and attempt % 10 == 0:
                size *= 0.9
            c = (float(self.rng.uniform(0, self.width)), float(self.rng.uniform(0, self.height)))
            h_mat = _card_homography(1.2 * size, 1.2 * size, c, 1.0, rotation, tilt)
            corners = cv2.perspectiveTransform(
                np.array(
                    [[[0, 0]], [[1.2 * size, 0]], [[1.2 * size, 1.2 * size]], [[0, 1.2 * size]]], np.float64
                ),
                h_mat,
            ).reshape(-1, 2)
            if (
                corners.min() >= 2
                and corners[:, 0].max() <= self.width - 2
                and corners[:, 1].max() <= self.height - 2
            ):
                return c, size
        return (self.width / 2, self.height / 2), size

    def render(self, scene: Scene) -> tuple[np.ndarray, list[Label]]:
        """Render `scene` (the same scene twice differs only in sensor noise)."""
        img = scene.background.copy()
        labels: list[Label] = []
        self.card = None
        if scene.shape is not None:
            box = self._draw_card(img, scene, scene.center)
            if box is not None:
                labels.append(Label(scene.shape, box))
            if self.record and not scene.lens:
                self.card = Painted("mark card", np.any(img != scene.background, axis=2))
        if scene.lens:
            img, labels = _through_lens(img, labels, scene.lens)
        out = cv2.multiply(img.astype(np.float32), cv2.merge([scene.light] * 3))
        out = _motion_blur(out, *scene.blur)
        if scene.noise > 0:
            noise = self.rng.standard_normal(out.shape, dtype=np.float32)
            out = cv2.scaleAdd(noise, scene.noise, out)
        frame: np.ndarray = np.clip(out, 0, 255, out=out).astype(np.uint8)
        if scene.jpeg:
            ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, scene.jpeg])
            decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR) if ok else None
            if decoded is not None:
                frame = np.asarray(decoded)
        return frame, labels

    # ------------------------------------------------------------------ background and clutter
    def _background(self) -> np.ndarray:
        rng, w, h = self.rng, self.width, self.height
        self.painted, self.background = [], "procedural"
        if self.bank and rng.random() < 0.85:
            pick = int(rng.integers(len(self.bank)))
            src, self.background = self.bank[pick], self.bank_names[pick]
            scale = max(w / src.shape[1], h / src.shape[0]) * rng.uniform(1.0, 1.6)
            big = cv2.resize(src, None, fx=scale, fy=scale, interpolation=cv2.INTER_LINEAR)
            y0 = int(rng.integers(0, big.shape[0] - h + 1))
            x0 = int(rng.integers(0, big.shape[1] - w + 1))
            img = np.ascontiguousarray(big[y0 : y0 + h, x0 : x0 + w])
            if rng.random() < 0.5:
                img = np.ascontiguousarray(img[:, ::-1])
        else:
            img = _procedural_background(rng, w, h)
        lo, hi = self.variation.distractors
        for _ in range(int(rng.integers(lo, hi + 1))):
            kind = self.variation.kinds[int(rng.integers(len(self.variation.kinds)))]
            before = img.copy() if self.record else None
            name = self._distractor(img, kind)
            if before is not None:
                self.painted.append(Painted(name or kind, np.any(img != before, axis=2)))
        return img

    def _distractor(self, img: np.ndarray, kind: str) -> str | None:
        """Draw one clutter of `kind`; a decoy card says what it carries ("decoy ..."), the rest None."""
        rng, w, h = self.rng, self.width, self.height
        cx, cy = float(rng.uniform(0, w)), float(rng.uniform(0, h))
        size = float(math.exp(rng.uniform(math.log(20), math.log(220))))
        colour = _dark_or_any(rng)
        if kind == "square":
            pts = _rotated_rect(cx, cy, size, size * rng.uniform(0.8, 1.2), rng.uniform(0, 90))
            if rng.random() < 0.5:
                cv2.fillPoly(img, [pts], colour, cv2.LINE_AA)
            else:
                cv2.polylines(
                    img, [pts], True, colour, max(2, int(size * rng.uniform(0.08, 0.2))), cv2.LINE_AA
                )
        elif kind == "disc":
            cv2.circle(img, (int(cx), int(cy)), int(size / 2), colour, -1, cv2.LINE_AA)
        elif kind == "sign":
            _draw_sign(img, rng, cx, cy, size)
        elif kind == "filled_triangle":
            # not a mark: a filled triangle that is not on a card, half the time painted on a plain
            # light wall or poster that runs on far beyond it (a card ends within about its width)
            if rng.random() < 0.5:
                wall = np.array([[cx - 3 * size, cy - 3 * size], [cx + 3 * size, cy + 3 * size]])
                wall += rng.uniform(-1.5, 1.5, size=(2, 2)) * size
                level = int(rng.integers(185, 250))
                cv2.rectangle(img, _point(wall[0]), _point(wall[1]), (level, level, level - 8), -1)
            r = size / 2
            a0 = rng.uniform(0, 2 * math.pi)
            verts = np.array(
                [
                    [cx + r * math.cos(a0 + k * 2 * math.pi / 3), cy + r * math.sin(a0 + k * 2 * math.pi / 3)]
                    for k in range(3)
                ]
            )
            verts[:, 1] = cy + (verts[:, 1] - cy) * rng.uniform(0.7, 1.0)  # a tilted sign
            cv2.fillPoly(img, [_fixed(verts)], _dark_or_any(rng), cv2.LINE_AA, shift=4)
        elif kind == "text":
            _draw_text(img, rng, (int(cx) - 100, int(cy)), colour)
        elif kind == "face":
            self._draw_face(img, cx, cy, size * 1.5)
        elif kind == "cable":
            pts = _bezier(rng, w, h)
            cv2.polylines(img, [pts], False, colour, int(rng.integers(2, 12)), cv2.LINE_AA)
        elif kind == "texture":
            _draw_texture(img, rng, cx, cy, size * 1.5)
        elif kind == "card":
            return self._draw_decoy_card(img, cx, cy, size)
        elif kind == "arrow":
            _draw_arrow(img, rng, cx, cy, size)
        elif kind in ("star", "check", "clock"):
            _draw_pictogram(img, rng, kind, cx, cy, size)
        elif kind == "crossing":
            _draw_crossing(img, rng, cx, cy, size)
        else:
            raise ValueError(f"unknown clutter kind {kind!r}: one of {', '.join(DISTRACTORS + EXTRA_DISTRACTORS)}")
        return None

    def _draw_decoy_card(self, img: np.ndarray, cx: float, cy: float, size: float) -> str:
        """A white card carrying a non-mark: square, filled disc, filled square or a word; returns which ("decoy
        outline square", "decoy disc", "decoy filled square", "decoy word")."""
        rng = self.rng
        side = size * 1.8
        card = np.full((int(side), int(side), 3), int(rng.integers(200, 256)), np.uint8)
        c = side / 2
        ink = tuple(int(x) for x in rng.integers(0, 60, size=3))
        what = rng.integers(4)
        t = max(2, int(size * rng.uniform(0.1, 0.18)))
        if what == 0:
            cv2.polylines(card, [_rotated_rect(c, c, size, size, 0)], True, ink, t, cv2.LINE_AA)
        elif what == 1:
            cv2.circle(card, (int(c), int(c)), int(size / 2), ink, -1, cv2.LINE_AA)
        elif what == 2:
            cv2.fillPoly(card, [_rotated_rect(c, c, size, size, 0)], ink, cv2.LINE_AA)
        else:
            word = "".join(rng.choice(list("AOXVTKQDRB"), size=int(rng.integers(3, 6))))
            scale = side / (40 * len(word))
            cv2.putText(
                card,
                word,
                (int(side * 0.05), int(c + 10 * scale)),
                cv2.FONT_HERSHEY_SIMPLEX,
                scale,
                ink,
                max(1, int(2 * scale)),
                cv2.LINE_AA,
            )
        h_mat = _card_homography(
            side, side, (cx, cy), 1.0, rng.uniform(-180, 180), (rng.uniform(-30, 30), rng.uniform(-30, 30))
        )
        _paste_warped(img, card, h_mat)
        return ("decoy outline square", "decoy disc", "decoy filled square", "decoy word")[int(what)]

    def _draw_face(self, img: np.ndarray, cx: float, cy: float, size: float) -> None:
        size = max(size, 40.0)
        if self.face is not None:
            face = cv2.resize(self.face, (int(size), int(size * 1.2)), interpolation=cv2.INTER_AREA)
            _paste(img, face, int(cx - size / 2), int(cy - size * 0.6))
            return
        # procedural: skin-coloured oval with eyes, brows and a mouth
        c = (int(cx), int(cy))
        cv2.ellipse(img, c, (int(size / 2), int(size * 0.6)), 0, 0, 360, (140, 170, 220), -1, cv2.LINE_AA)
        for dx in (-0.2, 0.2):
            e = (int(cx + dx * size), int(cy - 0.1 * size))
            cv2.ellipse(img, e, (int(size * 0.08), int(size * 0.05)), 0, 0, 360, (255, 255, 255), -1)
            cv2.circle(img, e, max(1, int(size * 0.035)), (40, 30, 20), -1, cv2.LINE_AA)
        cv2.ellipse(
            img,
            (c[0], int(cy + 0.25 * size)),
            (int(size * 0.18), int(size * 0.07)),
            0,
            0,
            180,
            (40, 40, 120),
            max(1, int(size * 0.03)),
            cv2.LINE_AA,
        )

    def _lighting(self, strength: float) -> np.ndarray:
        rng, v = self.rng, self.variation
        gw, gh = 32, 24
        yy, xx = np.mgrid[0:gh, 0:gw].astype(np.float32)
        gain = np.full((gh, gw), rng.uniform(*v.dim), np.float32)
        if strength > 0:
            ang = rng.uniform(0, 2 * math.pi)
            ramp = math.cos(ang) * (xx / gw - 0.5) + math.sin(ang) * (yy / gh - 0.5)
            gain *= 1.0 + strength * 0.9 * ramp
            # a soft shadow or a bright spot somewhere
            sx, sy, sr = rng.uniform(0, gw), rng.uniform(0, gh), rng.uniform(4, 12)
            blob = np.exp(-((xx - sx) ** 2 + (yy - sy) ** 2) / (2 * sr * sr))
            gain *= 1.0 + strength * rng.uniform(-0.5, 0.3) * blob
        gain = np.clip(gain, 0.2, 1.4)
        return cv2.resize(gain, (self.width, self.height), interpolation=cv2.INTER_CUBIC)

    # ------------------------------------------------------------------ the mark
    def _draw_card(self, img: np.ndarray, scene: Scene, center: tuple[float, float]) -> Box | None:
        s = scene.size
        # supersample small cards so the anti-aliased mark stays crisp before warping
        k = 4.0 if s < 80 else 2.0 if s < 160 else 1.0
        cw, ch = scene.card[0] * s * k, scene.card[1] * s * k
        card = np.empty((int(ch), int(cw), 3), np.uint8)
        card[:] = scene.paper
        if scene.by_hand is not None and scene.shape is not None:
            mark_pts = _draw_by_hand(
                card, scene.shape, (cw / 2, ch / 2), s * k, scene.stroke * s * k, scene.ink, scene.filled,
                np.random.default_rng(scene.by_hand),
            )
        else:
            mark_pts = _draw_mark(
                card,
                scene.shape,
                (cw / 2, ch / 2),
                s * k,
                scene.stroke * s * k,
                scene.ink,
                scene.skew,
                scene.filled,
            )
        if scene.sheen is not None:
            card = _add_light(card, scene.sheen.light(card.shape[:2], (cw / 2, ch / 2), s * k))
        if scene.fingers:
            # fingers over the card's bottom edge (or another: the card turned, drawn on, turned back),
            # their tips stopping short of the mark
            turned = np.ascontiguousarray(np.rot90(card, scene.finger_edge))
            th, tw = turned.shape[:2]
            fw = scene.finger_width * s * k
            tip = th / 2 + s * k / 2 + scene.finger_gap * s * k
            length = max(th - tip, 0.0) + fw
            lit = tuple(min(255, c + 25) for c in scene.skin)
            for f in range(scene.fingers):
                fx = tw / 2 + (f - (scene.fingers - 1) / 2) * 1.1 * fw + self.rng.uniform(-0.3, 0.3) * s * k
                centre = (int(fx), int(tip + length / 2))
                axes = (int(fw / 2), int(length / 2 + fw / 2))
                angle = float(self.rng.uniform(-12, 12))
                cv2.ellipse(turned, centre, axes, angle, 0, 360, scene.skin, -1, cv2.LINE_AA)
                inner = (max(1, axes[0] - 2), max(1, axes[1] - 2))
                cv2.ellipse(turned, centre, inner, 0, 0, 360, lit, -1, cv2.LINE_AA)
            card = np.ascontiguousarray(np.rot90(turned, -scene.finger_edge))
        if scene.hand:
            # fingers holding a bottom corner of the card
            hc = (int(cw * self.rng.choice([0.0, 1.0])), int(ch))
            cv2.ellipse(
                card,
                hc,
                (int(cw * 0.2), max(1, int(min(ch * 0.16, 0.9 * (ch - s * k) / 2)))),  # stays in the border
                0,
                0,
                360,
                (120, 150, 200),
                -1,
                cv2.LINE_AA,
            )
        h_mat = _card_homography(
            card.shape[1], card.shape[0], center, 1.0 / k, scene.rotation_deg, scene.tilt
        )
        _paste_warped(img, card, h_mat)
        proj = cv2.perspectiveTransform(mark_pts.reshape(-1, 1, 2).astype(np.float64), h_mat).reshape(-1, 2)
        x0, y0 = np.floor(proj.min(axis=0))
        x1, y1 = np.ceil(proj.max(axis=0))
        x0, y0 = max(0, int(x0)), max(0, int(y0))
        x1, y1 = min(self.width, int(x1)), min(self.height, int(y1))
        if x1 - x0 < 2 or y1 - y0 < 2:
            return None
        return (x0, y0, x1 - x0, y1 - y0)


def _draw_mark(
    card: np.ndarray,
    shape: Shape | None,
    c: tuple[float, float],
    s: float,
    t: float,
    ink: tuple[int, int, int],
    skew: float,
    filled: bool = False,
) -> np.ndarray:
    """Draw the mark (width `s`, stroke `t`) centred at `c`; return its outline points for the label."""
    cx, cy = c
    t = max(t, 1.5)
    if shape is Shape.O:
        r = (s - t) / 2
        cv2.circle(card, (int(cx), int(cy)), round(r), ink, round(t), cv2.LINE_AA)
        ang = np.linspace(0, 2 * math.pi, 64, endpoint=False)
        return np.stack([cx + (s / 2) * np.cos(ang), cy + (s / 2) * np.sin(ang)], axis=1)
    if shape is Shape.TRIANGLE:
        a = s  # side
        r_out = a / math.sqrt(3)  # circumradius
        verts = np.array(
            [
                [
                    cx + r_out * math.cos(math.radians(-90 + 120 * i)),
                    cy + r_out * math.sin(math.radians(-90 + 120 * i)),
                ]
                for i in range(3)
            ]
        )
        # centroid at c; inner triangle inset by the stroke width
        inr = a / (2 * math.sqrt(3))
        centre = np.array(c)
        inner = centre + (verts - centre) * max(0.05, (inr - t) / inr)
        cv2.fillPoly(card, [_fixed(verts)], ink, cv2.LINE_AA, shift=4)
        if not filled:
            paper = tuple(int(x) for x in card[0, 0])
            cv2.fillPoly(card, [_fixed(inner)], paper, cv2.LINE_AA, shift=4)
        return verts
    if shape is Shape.X:
        h = s / 2 - t / 2
        pts = []
        for bar in (45 + skew / 2, 135 - skew / 2):
            dx, dy = (
                h * math.cos(math.radians(bar)) * math.sqrt(2),
                h * math.sin(math.radians(bar)) * math.sqrt(2),
            )
            dx, dy = np.clip([dx, dy], -h, h)
            p0, p1 = (cx - dx, cy - dy), (cx + dx, cy + dy)
            cv2.line(
                card,
                (int(p0[0] * 16), int(p0[1] * 16)),
                (int(p1[0] * 16), int(p1[1] * 16)),
                ink,
                round(t),
                cv2.LINE_AA,
                shift=4,
            )
            for p in (p0, p1):
                pts += [
                    (p[0] + ox, p[1] + oy)
                    for ox, oy in ((t / 2, t / 2), (-t / 2, -t / 2), (t / 2, -t / 2), (-t / 2, t / 2))
                ]
        return np.array(pts)
    return np.array([[cx, cy]])


def _draw_by_hand(
    card: np.ndarray, shape: Shape, c: tuple[float, float], s: float, t: float, ink: tuple[int, int, int],
    filled: bool, rng: Rng,
) -> np.ndarray:
    """`_draw_mark`'s shapes as a person draws them with a pen (`Variation.hand_drawn`); the outline points."""
    centre = np.array(c, np.float64)
    if shape is Shape.O:
        # an oval, its axes up to 15 % apart and turned any way, its radius wavering by a few per cent;
        # the pen goes on past where it started, and not quite back onto its first line
        start, over = rng.uniform(0, 2 * math.pi), rng.uniform(0.05, 0.5)
        theta = np.linspace(start, start + 2 * math.pi + over, 90)
        aspect, turn = rng.uniform(0.85, 1.0), rng.uniform(0, math.pi)
        drift = np.linspace(0, rng.uniform(-0.35, 0.35) * t, theta.size)
        rad = (s - t) / 2 * (1 + _waver(rng, theta.size, 0.03)) + drift
        local = np.stack([rad * np.cos(theta), aspect * rad * np.sin(theta)], axis=1)
        rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
        path = centre + local @ rot.T
        return _pen(card, [path], t, ink, rng)
    if shape is Shape.TRIANGLE:
        # each corner of the exact triangle moved by up to a tenth of the size: uneven sides and angles
        r_out = s / math.sqrt(3)
        ang = np.radians(-90 + 120 * np.arange(3) + rng.uniform(-8, 8))
        verts = centre + r_out * np.stack([np.cos(ang), np.sin(ang)], axis=1) + rng.uniform(-0.1, 0.1, (3, 2)) * s
        verts += centre - verts.mean(axis=0)
        first = int(rng.integers(0, 3))
        corners = np.roll(verts, -first, axis=0)
        ring = np.vstack([corners, corners[:1], corners[0] + rng.uniform(0.0, 0.12) * (corners[1] - corners[0])])
        path = np.vstack([_wavy_line(rng, a, b, s) for a, b in itertools.pairwise(ring)])
        if filled:
            cv2.fillPoly(card, [_fixed(path)], ink, cv2.LINE_AA, shift=4)
        return _pen(card, [path], t, ink, rng)
    # X: two bowed bars of unequal length crossing up to 15 % off their middles, at 70-110 degrees
    bars = []
    mid = rng.uniform(-0.15, 0.15, 2) * s
    for k, bar in enumerate((45 + rng.uniform(-10, 10), 135 + rng.uniform(-10, 10))):
        half = (s - t) / 2 * math.sqrt(2) * rng.uniform(0.85, 1.0)
        d = np.array([math.cos(math.radians(bar)), math.sin(math.radians(bar))])
        a, b = centre + (mid[k] - half) * d, centre + (mid[k] + half) * d
        bars.append(_wavy_line(rng, a, b, s, bow=0.04))
    return _pen(card, bars, t, ink, rng)


def _waver(rng: Rng, n: int, amount: float) -> np.ndarray:
    """A smooth random wobble of n samples, at most about `amount` (two slow sine waves)."""
    x = np.linspace(0, 1, n)
    return amount * sum(
        rng.uniform(-1, 1) * np.sin(2 * math.pi * (rng.uniform(0.5, 2.5) * x + rng.uniform(0, 1))) for _ in range(2)
    ) / 2


def _wavy_line(rng: Rng, a: np.ndarray, b: np.ndarray, s: float, bow: float = 0.025) -> np.ndarray:
    """Points from a to b, bowed sideways by up to `bow` of the mark's size `s` and wavering by up to half that."""
    n = max(8, int(np.linalg.norm(b - a) / max(s, 1) * 40))
    x = np.linspace(0, 1, n)[:, None]
    normal = np.array([-(b - a)[1], (b - a)[0]]) / max(float(np.linalg.norm(b - a)), 1e-6)
    side = rng.uniform(-bow, bow) * s * np.sin(math.pi * x) + _waver(rng, n, bow / 2)[:, None] * s
    pts: np.ndarray = a + x * (b - a) + side * normal
    return pts


def _pen(card: np.ndarray, strokes: list[np.ndarray], t: float, ink: tuple[int, int, int], rng: Rng) -> np.ndarray:
    """Draw each stroke as a pen does: round ends and corners, the width swelling and thinning along the way
    (by up to 40 %); the points around the strokes, for the label."""
    for path in strokes:
        width = t * (1 + _waver(rng, len(path), 0.4))
        for (p, q), w in zip(itertools.pairwise(path), width[1:], strict=False):
            cv2.line(card, _sub(p), _sub(q), ink, max(1, round(w)), cv2.LINE_AA, shift=4)
    pts = np.vstack(strokes)
    return np.vstack([pts + (dx, dy) for dx in (-t / 2, t / 2) for dy in (-t / 2, t / 2)])


def _sub(p: np.ndarray) -> tuple[int, int]:
    """A point in OpenCV's fixed point (shift=4)."""
    return round(float(p[0]) * 16), round(float(p[1]) * 16)


def _point(p: np.ndarray) -> tuple[int, int]:
    return int(p[0]), int(p[1])


def _fixed(pts: np.ndarray) -> np.ndarray:
    return np.round(pts * 16).astype(np.int32).reshape(-1, 1, 2)


def _card_homography(
    w: float,
    h: float,
    center: tuple[float, float],
    scale: float,
    rot_deg: float,
    tilt_deg: tuple[float, float],
    focal: float = 700.0,
) -> np.ndarray:
    """Homography taking card pixels to frame pixels: scale, rotate in plane, tilt in 3-D, project."""
    src = np.array([[0, 0], [w, 0], [w, h], [0, h]], np.float64)
    pts = (src - [w / 2, h / 2]) * scale
    pts3 = np.concatenate([pts, np.zeros((4, 1))], axis=1)
    r = math.radians(rot_deg)
    rz = np.array([[math.cos(r), -math.sin(r), 0], [math.sin(r), math.cos(r), 0], [0, 0, 1]])
    ax, ay = (math.radians(a) for a in tilt_deg)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    p = pts3 @ (ry @ rx @ rz).T
    z = focal + p[:, 2]
    dst = np.stack([focal * p[:, 0] / z + center[0], focal * p[:, 1] / z + center[1]], axis=1)
    return cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32)).astype(np.float64)


def _paste_warped(img: np.ndarray, patch: np.ndarray, h_mat: np.ndarray) -> None:
    """Warp `patch` by `h_mat` into `img`, blending along the anti-aliased patch edge."""
    ph, pw = patch.shape[:2]
    corners = cv2.perspectiveTransform(
        np.array([[[0, 0]], [[pw, 0]], [[pw, ph]], [[0, ph]]], np.float64), h_mat
    )
    x0, y0 = np.floor(corners.reshape(-1, 2).min(axis=0)).astype(int)
    x1, y1 = np.ceil(corners.reshape(-1, 2).max(axis=0)).astype(int)
    x0, y0 = max(0, x0), max(0, y0)
    x1, y1 = min(img.shape[1], x1), min(img.shape[0], y1)
    if x1 <= x0 or y1 <= y0:
        return
    shift = np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1]], np.float64) @ h_mat
    size = (x1 - x0, y1 - y0)
    warped = cv2.warpPerspective(
        patch, shift, size, flags=cv2.INTER_AREA if np.abs(h_mat[0, 0]) < 0.6 else cv2.INTER_LINEAR
    )
    mask = cv2.warpPerspective(np.full((ph, pw), 255, np.uint8), shift, size, flags=cv2.INTER_LINEAR)
    m = (mask.astype(np.float32) / 255.0)[..., None]
    roi = img[y0:y1, x0:x1]
    roi[:] = (warped * m + roi * (1 - m)).astype(np.uint8)


def _paste(img: np.ndarray, patch: np.ndarray, x: int, y: int, where: np.ndarray | None = None) -> None:
    """`patch` into `img` with its corner at (x, y), cut at the frame's edges; only its `where` pixels if given."""
    h, w = patch.shape[:2]
    x0, y0, x1, y1 = max(0, x), max(0, y), min(img.shape[1], x + w), min(img.shape[0], y + h)
    if x1 > x0 and y1 > y0:
        part = patch[y0 - y : y1 - y, x0 - x : x1 - x]
        if where is None:
            img[y0:y1, x0:x1] = part
        else:
            keep = where[y0 - y : y1 - y, x0 - x : x1 - x]
            img[y0:y1, x0:x1][keep] = part[keep]


@functools.lru_cache(maxsize=4)
def _lens_maps(h: int, w: int, k: float) -> tuple[np.ndarray, np.ndarray]:
    """`_through_lens`'s remap: for every frame pixel, the scene pixel it shows (one lens, every frame:
    made once per frame size)."""
    cx, cy, f = w / 2, h / 2, w / 2
    corner = 1 + k * ((cx / f) ** 2 + (cy / f) ** 2)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    xd, yd = (xx - cx) / f, (yy - cy) / f
    gain = (1 + k * (xd * xd + yd * yd)) / corner
    return xd * gain * f + cx, yd * gain * f + cy


def _through_lens(img: np.ndarray, labels: list[Label], k: float) -> tuple[np.ndarray, list[Label]]:
    """The scene as a lens with barrel distortion `k` (`Variation.lens`) shows it, and the labels' boxes
    where the marks end up (the box around nine points of each: corners and edge midpoints)."""
    h, w = img.shape[:2]
    cx, cy, f = w / 2, h / 2, w / 2
    corner = 1 + k * ((cx / f) ** 2 + (cy / f) ** 2)
    out = cv2.remap(img, *_lens_maps(h, w, k), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)

    def shown_at(x: float, y: float) -> tuple[float, float]:
        """Where the scene's point (x, y) appears in the frame (fixed-point inversion of `gain`)."""
        xs, ys = (x - cx) / f, (y - cy) / f
        xf, yf = xs, ys
        for _ in range(30):
            g = (1 + k * (xf * xf + yf * yf)) / corner
            xf, yf = xs / g, ys / g
        return xf * f + cx, yf * f + cy

    moved = []
    for lab in labels:
        x, y, bw, bh = lab.box
        pts = [shown_at(x + bw * a, y + bh * b) for a in (0, 0.5, 1) for b in (0, 0.5, 1)]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        x0, y0 = int(math.floor(min(xs))), int(math.floor(min(ys)))
        moved.append(Label(lab.shape, (x0, y0, int(math.ceil(max(xs))) - x0, int(math.ceil(max(ys))) - y0)))
    return out, moved


def lens_calibration(k: float, width: int, height: int) -> Calibration:
    """The calibration a user would make of `Variation.lens` k's camera, in OpenCV's model (radial k1,
    k2, k3), fitted by least squares over the frame's radii. The pinhole scene has focal length f =
    width / 2; a ray at tan(angle) = r lands in the frame at F r (1 + k1 r^2 + k2 r^4 + k3 r^6), and the
    fit gives F (the lens's paraxial focal length: larger than f, the middle is magnified) and the k's.
    An undistorted frame shows the pinhole scene scaled about a point (`Undistorter.new_matrix` against f
    and the frame's centre)."""
    from services.vision.calibration import Calibration

    cx, cy, f = width / 2, height / 2, width / 2
    r_corner = math.hypot(cx / f, cy / f)
    r_frame = np.linspace(1e-3, r_corner * 1.02, 400)
    r_scene = r_frame * (1 + k * r_frame**2) / (1 + k * r_corner**2)
    basis = np.stack([np.ones_like(r_scene), r_scene**2, r_scene**4, r_scene**6], axis=1)
    a0, b1, b2, b3 = np.linalg.lstsq(basis, r_frame / r_scene, rcond=None)[0]
    matrix = np.array([[f * a0, 0, cx], [0, f * a0, cy], [0, 0, 1]], dtype=np.float64)
    distortion = np.array([[b1 / a0, b2 / a0, 0.0, 0.0, b3 / a0]])  # k1 k2 p1 p2 k3
    return Calibration(matrix, distortion, (width, height), f"lens k={k}")



def _motion_blur(img: np.ndarray, length: float, angle_deg: float) -> np.ndarray:
    if length < 1.5:
        return img
    n = math.ceil(length) | 1
    kernel = np.zeros((n, n), np.float32)
    c = n // 2
    dx, dy = math.cos(math.radians(angle_deg)) * length / 2, math.sin(math.radians(angle_deg)) * length / 2
    cv2.line(kernel, (round(c - dx), round(c - dy)), (round(c + dx), round(c + dy)), 1.0, 1, cv2.LINE_AA)
    kernel /= kernel.sum()
    return cv2.filter2D(img, -1, kernel)


def _draw_arrow(img: np.ndarray, rng: Rng, cx: float, cy: float, size: float) -> None:
    """Not a mark: an arrow (a sign's, a label's, a keyboard key's) whose head is a filled triangle, with a
    shaft of any length and width, sometimes a head at both ends; 70 % on a light label around it."""
    ang = rng.uniform(0, 2 * math.pi)
    u, n = np.array([math.cos(ang), math.sin(ang)]), np.array([-math.sin(ang), math.cos(ang)])
    head_len, head_w = size * rng.uniform(0.3, 0.6), size * rng.uniform(0.3, 0.7)
    shaft_w = max(2.0, head_w * rng.uniform(0.15, 0.5))
    tip = np.array([cx, cy]) + u * size / 2
    tail = np.array([cx, cy]) - u * size / 2
    if rng.random() < 0.7:  # the label: light, the arrow's box and a margin
        level = int(rng.integers(190, 256))
        label = _rotated_rect(cx, cy, size * rng.uniform(1.15, 1.6), head_w * rng.uniform(1.3, 2.2), math.degrees(ang))
        cv2.fillPoly(img, [label], (level, level, level - int(rng.integers(0, 12))), cv2.LINE_AA)
    ink = _dark_or_any(rng)
    heads = [(tip, u)] + ([(tail, -u)] if rng.random() < 0.2 else [])  # (point, direction) of each head
    bases = [point - d * head_len for point, d in heads]
    start = bases[1] if len(bases) > 1 else tail  # the shaft runs from the tail (or the second head) to the head
    shaft = np.array([start + n * shaft_w / 2, bases[0] + n * shaft_w / 2,
                      bases[0] - n * shaft_w / 2, start - n * shaft_w / 2])
    cv2.fillPoly(img, [_fixed(shaft)], ink, cv2.LINE_AA, shift=4)
    for (point, d), base in zip(heads, bases, strict=True):
        side = np.array([-d[1], d[0]])
        head = np.array([point, base + side * head_w / 2, base - side * head_w / 2])
        cv2.fillPoly(img, [_fixed(head)], ink, cv2.LINE_AA, shift=4)


def _rotated_rect(cx: float, cy: float, w: float, h: float, ang: float) -> np.ndarray:
    pts = cv2.boxPoints(((cx, cy), (w, h), ang))
    return np.round(pts).astype(np.int32).reshape(-1, 1, 2)


def _bezier(rng: Rng, w: int, h: int) -> np.ndarray:
    p = rng.uniform([-50, -50], [w + 50, h + 50], size=(4, 2))
    return np.round(_cubic(p, 40)).astype(np.int32).reshape(-1, 1, 2)


def _cubic(p: np.ndarray, n: int = 60) -> np.ndarray:
    """n points of the cubic Bezier curve with control points p (4, 2)."""
    tt = np.linspace(0, 1, n)[:, None]
    return (1 - tt) ** 3 * p[0] + 3 * (1 - tt) ** 2 * tt * p[1] + 3 * (1 - tt) * tt**2 * p[2] + tt**3 * p[3]


def _draw_crossing(img: np.ndarray, rng: Rng, cx: float, cy: float, size: float) -> None:
    """Not a mark: strokes crossing at (cx, cy), each running on well past it (three to ten times `size`: two short
    strokes crossing are an X, drawn without its card). 40 % one cable
    lying in a loop (a cubic whose inner control points swap sides, so it crosses itself once); else two cables or
    pen strokes crossing at 25-90 degrees, bent or nearly straight, each in its own width and, half the time, its own
    ink (a cable over a pen line)."""
    turn = rng.uniform(0, 2 * math.pi)
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    strokes: list[np.ndarray] = []
    if rng.random() < 0.4:
        reach, lift = size * rng.uniform(1.0, 4.0), size * rng.uniform(3.0, 6.0)
        p = np.array([[-reach, 0.0], [2.0 * reach, lift], [-2.0 * reach, lift], [reach, 0.0]])
        p += rng.normal(0, size * 0.1, p.shape)
        curve = _cubic(p, 120)
        gap = np.linalg.norm(curve[:, None] - curve[None], axis=2)
        gap[np.abs(np.subtract.outer(np.arange(120), np.arange(120))) < 15] = np.inf  # not a point and its neighbours
        i, j = np.unravel_index(np.argmin(gap), gap.shape)
        strokes.append(curve - (curve[i] + curve[j]) / 2)  # its knot at the point
    else:
        apart = rng.uniform(math.radians(25), math.radians(90))
        for ang in (0.0, apart):
            d = np.array([math.cos(ang), math.sin(ang)])
            n = np.array([-d[1], d[0]])
            a, b = size * rng.uniform(3.0, 10.0), size * rng.uniform(3.0, 10.0)
            bend = size * rng.uniform(-1.5, 1.5) * (rng.random() < 0.7)
            p = np.array([-a * d, -a / 3 * d + bend * n, b / 3 * d + bend * n, b * d])
            curve = _cubic(p, 80)
            strokes.append(curve - curve[np.argmin(np.linalg.norm(curve, axis=1))])  # through the point
    own_ink = rng.random() < 0.5
    ink = _dark_or_any(rng)
    for curve in strokes:
        pts = np.round(curve @ rot.T + (cx, cy)).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(img, [pts], False, _dark_or_any(rng) if own_ink else ink, int(rng.integers(2, 12)), cv2.LINE_AA)


def _draw_text(img: np.ndarray, rng: Rng, org: tuple[int, int], colour: tuple[int, int, int]) -> None:
    letters = string.ascii_uppercase + string.ascii_lowercase + "0123456789"
    for line in range(int(rng.integers(1, 4))):
        word = "".join(rng.choice(list(letters + "XOAXOV"), size=int(rng.integers(3, 9))))
        scale = float(rng.uniform(0.6, 2.5))
        cv2.putText(
            img,
            word,
            (org[0], org[1] + int(line * 32 * scale)),
            int(rng.choice([cv2.FONT_HERSHEY_SIMPLEX, cv2.FONT_HERSHEY_DUPLEX, cv2.FONT_HERSHEY_TRIPLEX])),
            scale,
            colour,
            int(rng.integers(1, 5)),
            cv2.LINE_AA,
        )


def _draw_sign(img: np.ndarray, rng: Rng, cx: float, cy: float, size: float) -> None:
    """Not a mark: a round sign - a ring with a bar across it (prohibition) or with a letter or number
    inside (parking, speed limit) - on a light plate, tilted."""
    r = max(10.0, size / 2)
    plate = np.full((int(2.6 * r), int(2.6 * r), 3), int(rng.integers(200, 256)), np.uint8)
    c = (int(1.3 * r), int(1.3 * r))
    ring = (int(rng.integers(0, 60)), int(rng.integers(0, 60)), int(rng.integers(150, 230)))
    if rng.random() < 0.3:
        ring = tuple(int(v) for v in rng.integers(0, 70, size=3))  # type: ignore[assignment]
    t = max(2, int(r * rng.uniform(0.12, 0.25)))
    cv2.circle(plate, c, int(r - t / 2), ring, t, cv2.LINE_AA)
    if rng.random() < 0.5:
        a = math.radians(float(rng.choice([45.0, 135.0])) + rng.uniform(-10, 10))
        d = (r - t) * np.array([math.cos(a), math.sin(a)])
        cv2.line(plate, _point(c - d), _point(c + d), ring, t, cv2.LINE_AA)
    else:
        text = str(rng.choice(["P", "30", "50", "X", "O", "!", "A"]))
        scale = r / (18 * max(1, len(text)))
        (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_DUPLEX, scale, max(1, int(2 * scale)))
        org = (c[0] - tw // 2, c[1] + th // 2)
        cv2.putText(
            plate,
            text,
            org,
            cv2.FONT_HERSHEY_DUPLEX,
            scale,
            (20, 20, 20),
            max(1, int(2 * scale)),
            cv2.LINE_AA,
        )
    _paste_plate(img, rng, plate, cx, cy)


def _paste_plate(img: np.ndarray, rng: Rng, plate: np.ndarray, cx: float, cy: float) -> None:
    """`plate` pasted centred at (cx, cy), turned in the image by up to 40 degrees and tilted up to 35."""
    h_mat = _card_homography(
        plate.shape[1],
        plate.shape[0],
        (cx, cy),
        1.0,
        rng.uniform(-40, 40),
        (rng.uniform(-35, 35), rng.uniform(-35, 35)),
    )
    _paste_warped(img, plate, h_mat)


def _draw_pictogram(img: np.ndarray, rng: Rng, kind: str, cx: float, cy: float, size: float) -> None:
    """Not a mark: a star (five or six points, filled or outlined), a check mark (a tick, half of them in
    their box) or a clock face (a ring with twelve ticks and two hands: its hole is not empty paper), in
    any ink, 70 % on a light plate (a sticker, a label, a wall clock's face), else straight on the scene."""
    r = max(10.0, size / 2)
    side = int(2.6 * r)
    on_plate = rng.random() < 0.7
    plate = np.full((side, side, 3), int(rng.integers(190, 256)), np.uint8)
    c = np.array([side / 2, side / 2])
    ink = _dark_or_any(rng)
    stroke = max(2, int(r * rng.uniform(0.1, 0.25)))
    if kind == "star":
        points = int(rng.choice([5, 5, 6]))
        ang = rng.uniform(0, 2 * math.pi) + np.arange(2 * points) * math.pi / points
        radii = np.where(np.arange(2 * points) % 2 == 0, r, r * rng.uniform(0.35, 0.55))
        star = c + np.stack([radii * np.cos(ang), radii * np.sin(ang)], axis=1)
        if rng.random() < 0.75:
            cv2.fillPoly(plate, [_fixed(star)], ink, cv2.LINE_AA, shift=4)
        else:
            cv2.polylines(plate, [_fixed(star)], True, ink, stroke, cv2.LINE_AA, shift=4)
    elif kind == "check":
        tick = c + np.array([[-0.75, -0.05], [-0.25, 0.55], [0.8, -0.7]]) * r * rng.uniform(0.75, 1.0, size=(3, 1))
        cv2.polylines(plate, [_fixed(tick)], False, ink, stroke, cv2.LINE_AA, shift=4)
        if rng.random() < 0.5:
            box = c + np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * r * 1.1
            cv2.polylines(plate, [_fixed(box)], True, ink, max(1, stroke // 2), cv2.LINE_AA, shift=4)
    else:  # clock
        cv2.circle(plate, _point(c), int(r - stroke / 2), ink, stroke, cv2.LINE_AA)
        for k in range(12):
            u = np.array([math.cos(k * math.pi / 6), math.sin(k * math.pi / 6)])
            cv2.line(plate, _point(c + u * r * 0.78), _point(c + u * r * (0.66 if k % 3 else 0.6)), ink,
                     max(1, stroke // 3), cv2.LINE_AA)
        for length, width in ((0.45, 0.6), (0.7, 0.35)):  # the hour and the minute hand
            a = rng.uniform(0, 2 * math.pi)
            tip = c + np.array([math.cos(a), math.sin(a)]) * r * length
            cv2.line(plate, _point(c), _point(tip), ink, max(1, int(stroke * width)), cv2.LINE_AA)
    if on_plate:
        _paste_plate(img, rng, plate, cx, cy)
        return
    ink_only = plate.min(axis=2) < plate[0, 0].min()  # not the plate's paper: only the ink goes onto the scene
    _paste(img, plate, int(cx - side / 2), int(cy - side / 2), ink_only)


def _draw_texture(img: np.ndarray, rng: Rng, cx: float, cy: float, size: float) -> None:
    s = max(8, int(size))
    cell = max(3, int(rng.integers(3, 16)))
    yy, xx = np.mgrid[0:s, 0:s]
    kind = rng.integers(3)
    if kind == 0:
        pat = (((yy // cell) + (xx // cell)) % 2) * 255
    elif kind == 1:
        pat = ((xx + yy) // cell % 2) * 255
    else:
        pat = (
            rng.integers(0, 2, size=(s // cell + 1, s // cell + 1)).repeat(cell, 0).repeat(cell, 1)[:s, :s]
            * 255
        )
    patch = np.repeat(pat.astype(np.uint8)[..., None], 3, axis=2)
    _paste(img, patch, int(cx - s / 2), int(cy - s / 2))


def _skin(rng: Rng) -> tuple[int, int, int]:
    """A skin tone (BGR) from dark brown to pale, lit or in shade."""
    t = float(rng.uniform(0.0, 1.0))  # 0: dark brown, 1: pale
    dark, pale = np.array([45.0, 65.0, 100.0]), np.array([165.0, 185.0, 225.0])
    tone = (dark + t * (pale - dark)) * float(rng.uniform(0.8, 1.1))
    return tuple(int(c) for c in np.clip(tone, 0, 230))  # type: ignore[return-value]


def _mark_ink(rng: Rng, colour_share: float) -> tuple[int, int, int]:
    """Dark grey ink, or (a `colour_share` of the time) red, blue or green marker ink (BGR)."""
    if rng.random() >= colour_share:
        return tuple(int(x) for x in rng.integers(0, 60, size=3))  # type: ignore[return-value]
    base = ((35, 35, 190), (150, 60, 25), (50, 130, 30))[int(rng.integers(3))]
    return tuple(int(np.clip(b + rng.integers(-20, 21), 0, 255)) for b in base)  # type: ignore[return-value]


def _dark_or_any(rng: Rng) -> tuple[int, int, int]:
    if rng.random() < 0.6:
        return tuple(int(x) for x in rng.integers(0, 70, size=3))  # type: ignore[return-value]
    return tuple(int(x) for x in rng.integers(0, 256, size=3))  # type: ignore[return-value]


def _procedural_background(rng: Rng, w: int, h: int) -> np.ndarray:
    """Low-frequency colour noise plus rectangles and stripes: a room-ish clutter without images."""
    small = rng.uniform(30, 220, size=(6, 8, 3)).astype(np.float32)
    img: np.ndarray = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    fine = rng.normal(0, 12, size=(h // 4, w // 4, 3)).astype(np.float32)
    img += cv2.resize(fine, (w, h), interpolation=cv2.INTER_LINEAR)
    img = np.clip(img, 0, 255).astype(np.uint8)
    for _ in range(int(rng.integers(3, 10))):
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        cv2.rectangle(
            img,
            (x, y),
            (x + int(rng.integers(20, 200)), y + int(rng.integers(20, 200))),
            _dark_or_any(rng),
            -1,
        )
    return img


def _load_backgrounds(names: tuple[str, ...] = SKIMAGE_BACKGROUNDS) -> list[tuple[str, np.ndarray]]:
    """The scikit-image samples of `names` that load here, with their names, as BGR."""
    try:
        from skimage import data
    except ImportError:
        log.info("scikit-image not importable: procedural backgrounds only")
        return []
    bank = []
    for name in names:
        try:
            img = np.asarray(getattr(data, name)())
        except (AttributeError, OSError, ValueError) as exc:  # needs a download, or a changed API
            log.debug("skipping sample image", name=name, error=str(exc))
            continue
        if img.dtype != np.uint8:
            img = (img.astype(np.float32) * (255.0 / max(1.0, float(img.max())))).astype(np.uint8)
        img = (
            cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
            if img.ndim == 2
            else cv2.cvtColor(img[..., :3], cv2.COLOR_RGB2BGR)
        )
        bank.append((name, img))
    return bank


def _load_face() -> np.ndarray | None:
    try:
        from skimage import data

        img = np.asarray(data.astronaut())
    except (ImportError, OSError, ValueError):
        return None
    return cv2.cvtColor(img[20:230, 150:330], cv2.COLOR_RGB2BGR)  # Eileen Collins's face
