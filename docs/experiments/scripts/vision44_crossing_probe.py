"""Crossing strokes probe (stop 78): frames holding no mark, only a cable or pen stroke that crosses itself (a loop)
or two that cross each other, drawn here (not by either generator) over plain, procedural and photo backgrounds;
counts the frames the detector reports a mark in, by shape. Stop 78 found that every false X round vision43's
proposer added on its tuning seeds was such a crossing.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 1 \
        [--set proposer_model=FILE ...] [--save DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "bench"))
from vision_bench import _detector  # noqa: E402  (the bench's own settings parsing)

from services.vision import synthetic  # noqa: E402

W, H = 640, 480
MODES = ("loop", "two", "straight")


def _loop(rng: np.random.Generator) -> np.ndarray:
    """A cable lying in a loop: a prolate trochoid's arch (it crosses itself once), scaled, turned, bent a little."""
    a, b = 1.0, rng.uniform(1.6, 3.0)
    t = np.linspace(-np.pi * rng.uniform(1.4, 2.2), np.pi * rng.uniform(1.4, 2.2), 200)
    pts = np.stack([a * t - b * np.sin(t), -b * np.cos(t)], 1)
    pts *= rng.uniform(12, 45)
    ang = rng.uniform(0, 2 * np.pi)
    rot = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    pts = pts @ rot.T + rng.uniform([120, 100], [W - 120, H - 100])
    return pts


def _stroke(rng: np.random.Generator, through: np.ndarray, ang: float, bend: float) -> np.ndarray:
    """A cable through `through` at angle `ang`, bent by `bend` (0: straight), running far past the crossing."""
    t = np.linspace(-1, 1, 120)[:, None]
    half = rng.uniform(150, 400)
    d = np.array([np.cos(ang), np.sin(ang)])
    n = np.array([-d[1], d[0]])
    return through + t * half * d + (t**2 - rng.uniform(0, 0.5)) * bend * half * n


def frame(rng: np.random.Generator, mode: str, backgrounds: list[np.ndarray]) -> np.ndarray:
    pick = rng.integers(3)
    if pick == 0:
        img = np.full((H, W, 3), rng.integers(90, 230), np.uint8)
    elif pick == 1 or not backgrounds:
        img = synthetic._procedural_background(rng, W, H)
    else:
        bg = backgrounds[int(rng.integers(len(backgrounds)))]
        img = cv2.resize(bg, (W, H))
    ink = tuple(int(v) for v in rng.integers(0, 90, 3))
    thick = int(rng.integers(2, 12))
    if mode == "loop":
        strokes = [_loop(rng)]
    else:
        at = rng.uniform([160, 120], [W - 160, H - 120])
        a0 = rng.uniform(0, np.pi)
        a1 = a0 + rng.uniform(np.pi / 5, np.pi - np.pi / 5)
        bend = 0.0 if mode == "straight" else 0.4
        strokes = [_stroke(rng, at, a0, rng.uniform(-bend, bend)), _stroke(rng, at, a1, rng.uniform(-bend, bend))]
    for s in strokes:
        cv2.polylines(img, [np.round(s * 16).astype(np.int32).reshape(-1, 1, 2)], False, ink, thick, cv2.LINE_AA,
                      shift=4)
    sigma = rng.uniform(0, 2.5)
    if sigma > 0.3:
        img = cv2.GaussianBlur(img, (0, 0), sigma)
    img = np.clip(img + rng.normal(0, rng.uniform(1, 6), img.shape), 0, 255).astype(np.uint8)
    ok, jpg = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(60, 95))])
    return cv2.imdecode(jpg, cv2.IMREAD_COLOR)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=200, help="per mode")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--set", action="append", default=[], help="detector setting KEY=VALUE (the bench's)")
    ap.add_argument("--save", type=Path, help="write the frames with a mark here")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    det = _detector(args.set)
    backgrounds = [img for _, img in synthetic._load_backgrounds()]
    if args.save:
        args.save.mkdir(parents=True, exist_ok=True)
    report: dict[str, object] = {"seed": args.seed, "frames_per_mode": args.frames, "set": args.set}
    for mode in MODES:
        rng = np.random.default_rng([args.seed, MODES.index(mode)])
        shapes: Counter[str] = Counter()
        with_mark = 0
        for i in range(args.frames):
            img = frame(rng, mode, backgrounds)
            found = det.detect(img)
            with_mark += bool(found)
            shapes.update(d.shape.value for d in found)
            if found and args.save:
                for d in found:
                    x, y, w, h = d.box
                    cv2.rectangle(img, (x, y), (x + w, y + h), (0, 0, 255), 2)
                cv2.imwrite(str(args.save / f"{mode}_{i:04d}.png"), img)
        report[mode] = {"frames_with_a_mark": with_mark, "marks": dict(shapes)}
    print(json.dumps(report))


if __name__ == "__main__":
    main()
