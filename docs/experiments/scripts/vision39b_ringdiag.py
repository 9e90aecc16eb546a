"""Round vision39b: which of `_clear_ring`'s tests refused each proposal that reached it (a proposed triangle the verifier
gave 0.7-0.9), and whether it lay on the frame's true triangle. As run, on a worktree with the `propose_ring` option
(commit 7a63020; removed after the probe):
    PYTHONPATH=$W .venv/bin/python docs/experiments/scripts/vision39b_ringdiag.py SEED HAND propose_ring=0.15"""
import sys, cv2, numpy as np, collections
from services.vision import detector as D
from services.vision.detector import MarkDetector, parse_settings, box_overlap
from services.vision.synthetic import SceneGenerator, Variation
from bench.vision_stages import ORDER
from schemas.messages import Shape
cv2.setNumThreads(1)
rows = []
orig = D._clear_ring
def why(gray, box, cfg):
    x, y, w, h = box; size = max(w, h)
    pad = max(1, round(cfg.border * size)); r = max(3, round(cfg.propose_ring * size))
    x0, y0, x1, y1 = x - pad - r, y - pad - r, x + w + pad + r, y + h + pad + r
    if x0 < 0 or y0 < 0 or x1 > gray.shape[1] or y1 > gray.shape[0]: return "frame", None
    roi = gray[y0:y1, x0:x1]; ring = np.full(roi.shape, 255, np.uint8); ring[r:r+h+2*pad, r:r+w+2*pad] = 0
    ink = D._percentile(gray[y:y+h, x:x+w], 10); n = cv2.countNonZero(ring); paper = D._masked_median(roi, ring, n)
    if paper - ink < cfg.min_contrast: return "faint", paper - ink
    dark = cv2.countNonZero(cv2.bitwise_and(cv2.inRange(roi, 0, ink + 0.5 * (paper - ink)), ring)) / n
    if dark > cfg.propose_ring_ink: return "ink", round(dark, 3)
    _, std = cv2.meanStdDev(roi, mask=ring)
    if float(std[0][0]) > cfg.max_margin_texture * (paper - ink): return "texture", round(float(std[0][0]) / (paper - ink), 2)
    return "ok", None
cur = {}
def spy(gray, box, cfg):
    out = orig(gray, box, cfg)
    lab = cur.get("label")
    true = lab is not None and lab.shape is Shape.TRIANGLE and box_overlap(box, lab.box) >= 0.5
    rows.append((true, why(gray, box, cfg), box, lab.box if lab else None))
    return out
D._clear_ring = spy
det = MarkDetector(parse_settings(sys.argv[3:]))
for seed, hand in ((int(sys.argv[1]), float(sys.argv[2])),):
    g = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
    for i in range(1000):
        img, labels = g.render(g.scene(ORDER[i % 4]))
        cur["label"] = labels[0] if labels else None
        det.detect(img)
c = collections.Counter((t, w[0]) for t, w, *_ in rows)
print(c)
for t, w, b, lb in rows:
    if t: print(w, b, lb)
