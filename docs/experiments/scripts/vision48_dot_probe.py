"""Round vision48's probe (neither tuning nor held-out data): small solid round things that are not triangles, drawn
with OpenCV on the tuning generator's mark-free frames, one a frame; counts the frames with a false TRIANGLE (and any
false mark) per kind for each detector config given. Written for this round, after looking at a spent blind seed's
false triangles (853: dot stickers on small cards) and before any run of its held-out or fresh blind seeds.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision48_dot_probe.py SEED N "NAME KEY=VALUE ..." ...
Kinds: a dot (a filled disc, 8-40 px across), on a small light card or sticker (70 %) or straight on the scene; a
tilted dot (an ellipse, axes 1 : 0.45-0.8); a button (a filled disc with a lighter rim drawn round it); a filled
rounded square (a square with corners rounded by a quarter of its side, as a key or an app icon); and, as the
controls, a small filled triangle and a small outlined triangle on a card (TRIANGLE marks under the contract: their
rows count the frames where a TRIANGLE is found, what a config costs on small triangles). Any ink; Gaussian blur up
to 2 px; JPEG 50-95."""

import math
import sys

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator

cv2.setNumThreads(1)
KINDS = ("dot", "tilted dot", "button", "rounded square", "filled triangle (a mark: control)",
         "outlined triangle (a mark: control)")
INKS = ((20, 20, 20), (40, 40, 200), (150, 60, 20), (30, 150, 30), (60, 60, 60), (20, 20, 220), (160, 40, 160))


def draw(rng: np.random.Generator, kind: str, img: np.ndarray) -> np.ndarray:
    h, w = img.shape[:2]
    d = float(rng.uniform(8, 40))  # the shape's width, px
    r = d / 2
    c = (float(rng.uniform(2 * d + 10, w - 2 * d - 10)), float(rng.uniform(2 * d + 10, h - 2 * d - 10)))
    ci = (int(round(c[0] * 16)), int(round(c[1] * 16)))  # 4 bits of sub-pixel position
    ink = tuple(int(v) for v in INKS[int(rng.integers(len(INKS)))])
    rot = float(rng.uniform(0, 360))
    mark = kind.endswith("control)")
    if mark or rng.random() < 0.7:
        pad = r * rng.uniform(1.4, 2.4)
        paper = tuple(int(v) for v in rng.integers(200, 250, 3))
        if not mark and rng.random() < 0.4:
            cv2.circle(img, ci, int(pad * 16), paper, -1, cv2.LINE_AA, 4)
        else:
            box = cv2.boxPoints(((c[0], c[1]), (2 * pad, 2 * pad), float(rng.uniform(-20, 20))))
            cv2.fillConvexPoly(img, np.round(box * 16).astype(np.int32), paper, cv2.LINE_AA, 4)
    if kind in ("dot", "tilted dot"):
        minor = 1.0 if kind == "dot" else float(rng.uniform(0.45, 0.8))
        cv2.ellipse(img, ci, (int(r * 16), int(r * minor * 16)), rot, 0, 360, ink, -1, cv2.LINE_AA, 4)
    elif kind == "button":
        rim = tuple(int(min(255, v + 90)) for v in ink)
        cv2.circle(img, ci, int(r * 16), ink, -1, cv2.LINE_AA, 4)
        cv2.circle(img, ci, int(r * 0.8 * 16), rim, max(1, int(0.12 * r)), cv2.LINE_AA, 4)
    elif kind == "rounded square":
        k = 0.25 * d
        pts = []
        for qx, qy, a0 in ((1, 1, 0), (-1, 1, 90), (-1, -1, 180), (1, -1, 270)):
            for a in range(a0, a0 + 91, 15):
                t = math.radians(a)
                pts.append((qx * (r - k) + k * math.cos(t), qy * (r - k) + k * math.sin(t)))
        p = np.array(pts)
        t = math.radians(rot)
        p = p @ np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]]) + c
        cv2.fillPoly(img, [np.round(p * 16).astype(np.int32)], ink, cv2.LINE_AA, 4)
    else:  # a triangle mark
        t = math.radians(rot)
        p = np.array([(c[0] + r * 1.1 * math.cos(t + k * 2 * math.pi / 3), c[1] + r * 1.1 * math.sin(t + k * 2 * math.pi / 3))
                      for k in range(3)])
        if kind.startswith("filled"):
            cv2.fillConvexPoly(img, np.round(p * 16).astype(np.int32), ink, cv2.LINE_AA, 4)
        else:
            cv2.polylines(img, [np.round(p * 16).astype(np.int32)], True, ink, max(2, int(0.18 * d)), cv2.LINE_AA, 4)
    s = float(rng.uniform(0, 2.0))
    if s > 0.3:
        img = cv2.GaussianBlur(img, (0, 0), s)
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(50, 96))])
    return cv2.imdecode(buf, cv2.IMREAD_COLOR)


def main() -> None:
    seed, n = int(sys.argv[1]), int(sys.argv[2])
    configs = [(a.split()[0], MarkDetector(parse_settings(a.split()[1:]))) for a in sys.argv[3:]]
    gen = SceneGenerator(seed=seed)
    rng = np.random.default_rng(seed)
    print(f"seed {seed}, {n} frames a kind; frames with a TRIANGLE (with any mark) per config", flush=True)
    print("kind".ljust(38) + "".join(name.rjust(16) for name, _ in configs), flush=True)
    for kind in KINDS:
        tri = [0] * len(configs)
        anym = [0] * len(configs)
        for _ in range(n):
            img, _ = gen.frame(None)
            img = draw(rng, kind.split(" (")[0], img.copy())
            for j, (_, det) in enumerate(configs):
                found = det.detect(img)
                tri[j] += any(d.shape is Shape.TRIANGLE for d in found)
                anym[j] += bool(found)
        print(kind.ljust(38) + "".join(f"{a} ({b})".rjust(16) for a, b in zip(tri, anym, strict=True)), flush=True)


if __name__ == "__main__":
    main()
