"""Round vision47's probe (neither tuning nor held-out data): round things that are not O marks, drawn with OpenCV on
the tuning generator's mark-free frames, one a frame; counts the frames with a false O (and any false mark) per kind
for each detector config given. Written for this round, before any run of its held-out or blind seeds.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47_round_probe.py SEED N "NAME KEY=VALUE ..." ...
Kinds: a clock face (ring, twelve ticks, two hands, a hub), a smiley (ring, two eyes, a smile), a prohibition sign
(ring and a bar across), a power symbol (a ring open at the top, a stroke down to its middle), a target (two or three
rings and a dot), a wheel (ring, three to five spokes, a hub); and, as the control, a plain ring: under the contract
that is an O mark (a ring on a light surface), so its row says what a config costs on an O-like shape, not what it
gets wrong. 70 % on a light label (a sticker, a sign, a wall clock's face), else straight on the scene; any ink;
Gaussian blur up to 2.5 px; JPEG 50-95."""

import math
import sys

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator

cv2.setNumThreads(1)
KINDS = ("clock", "smiley", "prohibition", "power", "target", "wheel", "ring (an O: control)")
INKS = ((20, 20, 20), (40, 40, 160), (150, 60, 20), (30, 110, 30), (60, 60, 60), (20, 20, 200))


def draw(rng: np.random.Generator, kind: str, img: np.ndarray) -> np.ndarray:
    h, w = img.shape[:2]
    r = float(rng.uniform(20, 90))
    c = (float(rng.uniform(r + 15, w - r - 15)), float(rng.uniform(r + 15, h - r - 15)))
    ci = (int(c[0]), int(c[1]))
    ink = tuple(int(v) for v in INKS[int(rng.integers(len(INKS)))])
    t = max(2, int(r * rng.uniform(0.1, 0.2)))
    rot = float(rng.uniform(0, 2 * math.pi))
    if rng.random() < 0.7:
        pad = r * rng.uniform(1.15, 1.6)
        paper = tuple(int(v) for v in rng.integers(200, 250, 3))
        if rng.random() < 0.5:
            cv2.circle(img, ci, int(pad), paper, -1, cv2.LINE_AA)
        else:
            cv2.rectangle(img, (int(c[0] - pad), int(c[1] - pad)), (int(c[0] + pad), int(c[1] + pad)), paper, -1)

    def at(rad: float, ang: float) -> tuple[int, int]:
        return int(c[0] + rad * math.cos(ang)), int(c[1] + rad * math.sin(ang))

    if kind == "power":
        cv2.ellipse(img, ci, (int(r), int(r)), math.degrees(rot) - 90, 35, 325, ink, t, cv2.LINE_AA)
        cv2.line(img, at(1.1 * r, rot - math.pi / 2), ci, ink, t, cv2.LINE_AA)
    else:
        cv2.circle(img, ci, int(r), ink, t, cv2.LINE_AA)
    if kind == "clock":
        for k in range(12):
            a = rot + k * math.pi / 6
            cv2.line(img, at(0.72 * r, a), at(0.86 * r, a), ink, max(1, t // 2), cv2.LINE_AA)
        cv2.line(img, ci, at(0.5 * r, float(rng.uniform(0, 2 * math.pi))), ink, max(2, t // 2 + 1), cv2.LINE_AA)
        cv2.line(img, ci, at(0.75 * r, float(rng.uniform(0, 2 * math.pi))), ink, max(1, t // 2), cv2.LINE_AA)
        cv2.circle(img, ci, max(2, t // 2 + 1), ink, -1, cv2.LINE_AA)
    elif kind == "smiley":
        for s in (-1, 1):
            cv2.circle(img, at(0.38 * r, rot - math.pi / 2 + s * 0.7), max(2, int(0.1 * r)), ink, -1, cv2.LINE_AA)
        cv2.ellipse(img, ci, (int(0.55 * r), int(0.55 * r)), math.degrees(rot), 20, 160, ink, max(2, t // 2 + 1),
                    cv2.LINE_AA)
    elif kind == "prohibition":
        cv2.line(img, at(r, rot), at(r, rot + math.pi), ink, t, cv2.LINE_AA)
    elif kind == "target":
        for f in (0.62, 0.3)[: int(rng.integers(1, 3))]:
            cv2.circle(img, ci, max(3, int(f * r)), ink, max(2, int(t * 0.8)), cv2.LINE_AA)
        cv2.circle(img, ci, max(2, int(0.1 * r)), ink, -1, cv2.LINE_AA)
    elif kind == "wheel":
        n = int(rng.integers(3, 6))
        for k in range(n):
            cv2.line(img, ci, at(r, rot + k * 2 * math.pi / n), ink, max(2, t // 2 + 1), cv2.LINE_AA)
        cv2.circle(img, ci, max(3, int(0.18 * r)), ink, -1, cv2.LINE_AA)
    s = float(rng.uniform(0, 2.5))
    if s > 0.3:
        img = cv2.GaussianBlur(img, (0, 0), s)
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(50, 96))])
    return cv2.imdecode(buf, cv2.IMREAD_COLOR)


def main() -> None:
    seed, n = int(sys.argv[1]), int(sys.argv[2])
    configs = [(a.split()[0], MarkDetector(parse_settings(a.split()[1:]))) for a in sys.argv[3:]]
    gen = SceneGenerator(seed=seed)
    rng = np.random.default_rng(seed)
    print(f"seed {seed}, {n} frames a kind; frames with a false O (with any false mark) per config", flush=True)
    print("kind".ljust(22) + "".join(name.rjust(16) for name, _ in configs), flush=True)
    for kind in KINDS:
        o = [0] * len(configs)
        anym = [0] * len(configs)
        for _ in range(n):
            img, _ = gen.frame(None)
            img = draw(rng, kind.split()[0], img.copy())
            for j, (_, det) in enumerate(configs):
                found = det.detect(img)
                o[j] += any(d.shape is Shape.O for d in found)
                anym[j] += bool(found)
        print(kind.ljust(22) + "".join(f"{a} ({b})".rjust(16) for a, b in zip(o, anym, strict=True)), flush=True)


if __name__ == "__main__":
    main()
