"""Round vision34's copy of vision21_triclutter_probe.py: every kind, with the detector settings given.
Probe (neither tuning nor held-out data): triangle-like things that are not marks, drawn with OpenCV on the
tuning generator's mark-free frames; counts the frames with a false mark and the false marks per kind.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py [KEY=VALUE ...]
(detector settings as `bench/vision_bench.py --set` takes them, e.g. hand_triangle=0.8)."""
import sys, math
import cv2, numpy as np
from services.vision.detector import MarkDetector, parse_settings
from services.vision.synthetic import SceneGenerator
cv2.setNumThreads(1)
rng = np.random.default_rng(7)
gen = SceneGenerator(seed=7)
det = MarkDetector(parse_settings(sys.argv[1:]))

def tri(c, r, rot):
    return np.array([(c[0] + r * math.cos(rot + k * 2 * math.pi / 3), c[1] + r * math.sin(rot + k * 2 * math.pi / 3)) for k in range(3)], np.int32)

def draw(kind, img):
    h, w = img.shape[:2]
    r = float(rng.uniform(25, 90)); c = (int(rng.uniform(r + 10, w - r - 10)), int(rng.uniform(r + 10, h - r - 10)))
    rot = float(rng.uniform(0, 2 * math.pi))
    if kind == "play button":  # white triangle in a dark disc (a video player's icon)
        cv2.circle(img, c, int(r), (40, 40, 40), -1, cv2.LINE_AA)
        cv2.fillPoly(img, [tri(c, 0.5 * r, 0.0)], (235, 235, 235), cv2.LINE_AA)
    elif kind == "warning sign":  # red-rimmed triangle with '!' on a white sign, no card around it
        cv2.fillPoly(img, [tri(c, r, -math.pi / 2)], (30, 30, 200), cv2.LINE_AA)
        cv2.fillPoly(img, [tri(c, 0.72 * r, -math.pi / 2)], (240, 240, 240), cv2.LINE_AA)
        cv2.putText(img, "!", (c[0] - int(0.1 * r), c[1] + int(0.25 * r)), cv2.FONT_HERSHEY_DUPLEX, r / 45, (20, 20, 20), max(1, int(r / 20)), cv2.LINE_AA)
    elif kind == "roof":  # a dark filled triangle on a bright wall (house roof, pennant)
        cv2.fillPoly(img, [tri(c, r, rot)], tuple(int(v) for v in rng.uniform(0, 90, 3)), cv2.LINE_AA)
    elif kind == "delta text":  # Greek capital delta and A/V letters in a line of text
        x0 = max(5, c[0] - 150)
        cv2.putText(img, "AVA VAV LAVA", (x0, c[1]), cv2.FONT_HERSHEY_SIMPLEX, r / 40, (20, 20, 20), max(1, int(r / 18)), cv2.LINE_AA)
    elif kind == "arrow":  # a filled arrow head on a white label
        cv2.rectangle(img, (c[0] - int(1.3 * r), c[1] - int(1.3 * r)), (c[0] + int(1.3 * r), c[1] + int(1.3 * r)), (235, 235, 235), -1)
        cv2.fillPoly(img, [tri(c, r, rot)], (20, 20, 20), cv2.LINE_AA)
        cv2.line(img, c, (int(c[0] - 1.2 * r * math.cos(rot)), int(c[1] - 1.2 * r * math.sin(rot))), (20, 20, 20), max(3, int(r / 4)))
    return img

for kind in ("play button", "warning sign", "roof", "delta text", "arrow"):
    n = 150; falses = {"X": 0, "O": 0, "TRIANGLE": 0}; frames = 0
    for i in range(n):
        img, _ = gen.frame(None)
        img = draw(kind, img.copy())
        found = det.detect(img)
        frames += bool(found)
        for d in found:
            falses[d.shape.value] += 1
    print(f"{kind:14s} frames with a mark {frames}/{n}  false {falses}", flush=True)

