"""Stop 117's diagnostic (tuning data only): where a lamp's highlight hides triangles, and whether a second network
tells them from arrows. For every verifier candidate over a true triangle under `--glare 1`'s spot (tuning seed
7263) and every candidate on mark-free frames whose clutter is arrows only (seed 7264, as vision69_arrows.py draws
them): the committed model's, the glossy raiser's (joined to the committed veto, made as docs/experiments/README.md
says, given as RAISER) and the hand-triangle network's TRIANGLE probabilities.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/stop117_glare_triangles.py RAISER 7263 500 7264 300"""
import sys
from pathlib import Path

import cv2
import numpy as np

from bench.glare import glare_spot
from schemas.messages import Shape
from services.vision.detector import MarkDetector, _up, box_overlap, parse_settings
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import CLASSES, TRIANGLES_PATH, Verifier, claim

cv2.setNumThreads(1)
raiser, hand = Verifier.load(Path(sys.argv[1])), Verifier.load(TRIANGLES_PATH)
glare_seed, glare_n, arrow_seed, arrow_n = (int(a) for a in sys.argv[2:6])
T = CLASSES.index(Shape.TRIANGLE)
rows: list[dict] = []  # the last frame's candidates
verify = MarkDetector._verify


def recorded(self: MarkDetector, pending: list) -> list:
    if pending:
        patches = np.stack([self._crops(p) for p in pending])
        claims = np.stack([claim(p.shape) for p in pending])
        probs = [v.probabilities(patches, claims)[:, T] for v in (self.verifier, raiser, hand)]
        for j, p in enumerate(pending):
            rows.append({"loose": p.shape is None, "claimed_t": p.shape is Shape.TRIANGLE and not p.rescue,
                         "box": _up(p.box, p.level.f), "b": probs[0][j], "r": probs[1][j], "h": probs[2][j]})
    return verify(self, pending)


MarkDetector._verify = recorded  # type: ignore[method-assign]
det = MarkDetector(parse_settings([]))
missed = []  # per missed triangle: its candidates
gen = SceneGenerator(seed=glare_seed, variation=Variation())
for i in range(glare_n):
    img, labels = gen.render(gen.scene(Shape.TRIANGLE))
    img, _ = glare_spot(img, np.random.default_rng((glare_seed, i, 1)), 1.0, labels[0].box)
    rows.clear()
    found = det.detect(img)
    if not any(d.shape is Shape.TRIANGLE and box_overlap(d.box, labels[0].box) >= 0.5 for d in found):
        missed.append([c for c in rows if box_overlap(c["box"], labels[0].box) >= 0.5])
kinds = {"claimed triangle": 0, "loose only": 0, "other claim only": 0, "no candidate": 0}
for over in missed:
    key = ("claimed triangle" if any(c["claimed_t"] for c in over) else "loose only" if any(c["loose"] for c in over)
           else "other claim only" if over else "no candidate")
    kinds[key] += 1
print(f"glare seed {glare_seed}: {len(missed)} of {glare_n} triangles missed; {kinds}")
arrows = []  # per arrow frame: its candidates
gen = SceneGenerator(seed=arrow_seed, variation=Variation(kinds=("arrow",), distractors=(2, 5)))
false_t = 0
for _ in range(arrow_n):
    rows.clear()
    false_t += sum(d.shape is Shape.TRIANGLE for d in det.detect(gen.frame(None)[0]))
    arrows.append(list(rows))
print(f"arrow seed {arrow_seed}: {false_t} false triangles in {arrow_n} frames")


def new(c: dict, kind: str, r_at: float, h_at: float) -> bool:
    """A candidate the base refuses that the raiser's TRIANGLE (and the hand network's) would pass."""
    bar = 0.9 if kind == "loose" else 0.8  # the committed loose and claimed TRIANGLE thresholds
    return c[kind] and c["b"] < bar and c["r"] >= r_at and c["h"] >= h_at and (kind == "loose" or c["h"] < 0.8)


for kind in ("claimed_t", "loose"):
    for r_at in (0.5, 0.8, 0.9, 0.95):
        for h_at in (0.0, 0.3, 0.5, 0.7):
            m = sum(any(new(c, kind, r_at, h_at) for c in over) for over in missed)
            a = sum(any(new(c, kind, r_at, h_at) for c in frame) for frame in arrows)
            print(f"{kind:9s} raiser >= {r_at:.2f}, hand >= {h_at:.1f}: missed triangles with such a row {m:3d}; "
                  f"arrow frames {a:3d}")
