"""Round vision71c's speed condition: the base and one variant timed in one sitting on the same frames, alternating
(the order swapped every pass), best of PASSES passes each, in CPU seconds of this process with OpenCV on one thread.
Runs made minutes apart differ by about 4 % on a shared 2-core machine (round vision71b); interleaving cancels that.
    PYTHONPATH=<tree> .venv/bin/python docs/experiments/scripts/vision71c_speed.py SPLIT SEED FRAMES PASSES KEY=VALUE...
Prints one JSON line: frames per CPU-second of each, and the variant's over the base's."""

import json
import sys
import time

import cv2

from bench.vision_bench import _generator
from services.vision.detector import MarkDetector, parse_settings
from services.vision.verifier import CLASSES


def main(argv: list[str]) -> None:
    split, seed, n, passes, settings = argv[0], int(argv[1]), int(argv[2]), int(argv[3]), argv[4:]
    cv2.setNumThreads(1)
    frame_of = _generator(split, seed)
    frames = [frame_of(CLASSES[i % len(CLASSES)])[0] for i in range(n)]
    detectors = {"base": MarkDetector(parse_settings([])), "var": MarkDetector(parse_settings(settings))}
    for detector in detectors.values():  # warm up: the verifier's session and the caches
        for frame in frames[:20]:
            detector.detect(frame)
    best = dict.fromkeys(detectors, 0.0)
    for rep in range(passes):
        order = list(detectors.items())
        for name, detector in order if rep % 2 == 0 else order[::-1]:
            start = time.process_time()
            for frame in frames:
                detector.detect(frame)
            best[name] = max(best[name], len(frames) / (time.process_time() - start))
    print(json.dumps({"split": split, "seed": seed, "frames": n, "passes": passes, "settings": settings,
                      "base_fps": round(best["base"], 1), "var_fps": round(best["var"], 1),
                      "ratio": round(best["var"] / best["base"], 4)}))


if __name__ == "__main__":
    main(sys.argv[1:])
