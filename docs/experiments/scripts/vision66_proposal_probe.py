"""Round vision66's probe (stop 114): for each mark the detector misses under a bench highlight (`bench/glare.py`), did
the proposer propose it (peak >= 0.3, box overlap >= 0.5), and did the verifier give the proposed shape its bar?

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision66_proposal_probe.py SEED FRAMES PEAK

Run on tuning seed 7247 (a diagnostic seed since stop 113), 400 frames, peak 1.
"""

import sys
from collections import Counter

import cv2
import numpy as np

from bench.glare import glare_spot
from bench.vision_bench import CLASSES
from services.vision import detector as D
from services.vision.detector import box_overlap
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import claim


def fate(det: D.MarkDetector, img: np.ndarray, shape: D.Shape, box: tuple[int, int, int, int]) -> str:
    """What became of the true mark in `box`: found, or where the proposal path lost it."""
    if any(d.shape is shape and box_overlap(d.box, box) >= 0.5 for d in det.detect(img)):
        return "found"
    gray = D.to_gray(img)
    proposed = [p for p in det.proposer.propose(gray, 0.3) if box_overlap(p.box, box) >= 0.5]
    if not proposed:
        weak = [p for p in det.proposer.propose(gray, 0.1) if box_overlap(p.box, box) >= 0.5]
        return "not proposed (a peak under 0.3 only)" if weak else "not proposed"
    p = max(proposed, key=lambda p: p.score)
    if p.shape is not shape:
        return "proposed as another shape"
    row = det.verifier.probabilities(det.proposal_crops(gray, p.box)[None], claim(None)[None])[0]
    k = D.CLASSES.index(shape)
    need = det.config.propose_thresholds[k]
    if 0 < det.config.propose_sure[k] <= p.score:
        need = min(need, det.config.propose_sure_thresholds[k])
    return "proposed, the verifier under its bar" if row[k] < need else "proposed and named, lost later"


def main() -> None:
    cv2.setNumThreads(1)
    seed, n, peak = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=0.5))
    det = D.MarkDetector(D.DetectorConfig())
    counts: Counter[tuple[str, str]] = Counter()
    for i in range(n):
        shape = CLASSES[i % 4]
        img, labels = gen.frame(shape)
        box = labels[0].box if labels else None
        if peak:
            img, _ = glare_spot(img, np.random.default_rng((seed, i, 1)), peak, box)
        if shape is not None and box is not None:
            counts[(shape.value, fate(det, img, shape, box))] += 1
    for key in sorted(counts):
        print(*key, counts[key], sep="\t")


if __name__ == "__main__":
    main()
