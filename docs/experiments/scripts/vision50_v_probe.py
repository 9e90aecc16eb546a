"""Round vision50's probe (tuning generator, its clutter kinds "clock" and "check" added: each frame's clutter may be a
clock face with two hands or a check mark, which the default kinds never draw): for each detector config given, on
the same frames, the frames with a false TRIANGLE and with any false mark among the mark-free ones, and the triangles
and all marks found on the frames that hold one (the bench's box rule). Written for this round, after looking at spent
blind seeds' false triangles (853 and 863: a clock's two hands meeting at an angle, named a triangle as a loose
candidate) and before any run of its held-out or fresh blind seeds.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision50_v_probe.py SEED FRAMES HAND "NAME KEY=VALUE ..." ...
HAND: Variation.hand_variety and hand_drawn (fingers of every kind over the card, marks drawn by hand)."""

import sys

import cv2

from schemas.messages import Shape
from services.vision.detector import MarkDetector, box_overlap, parse_settings
from services.vision.synthetic import DISTRACTORS, SceneGenerator, Variation

cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)


def main() -> None:
    seed, frames, hand = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    configs = []
    for arg in sys.argv[4:]:
        name, _, settings = arg.partition(" ")
        configs.append((name, MarkDetector(parse_settings(settings))))
    gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand,
                                                        kinds=DISTRACTORS + ("clock", "check")))
    counts = {name: dict(false_t=0, false_any=0, found_t=0, found=0) for name, _ in configs}
    n_free = n_t = n_marks = 0
    for i in range(frames):
        truth = ORDER[i % 4]
        img, labels = gen.render(gen.scene(truth))
        lab = labels[0] if labels else None
        n_free += lab is None
        n_marks += lab is not None
        n_t += lab is not None and lab.shape is Shape.TRIANGLE
        for name, det in configs:
            found = det.detect(img)
            c = counts[name]
            if lab is None:
                c["false_t"] += any(d.shape is Shape.TRIANGLE for d in found)
                c["false_any"] += bool(found)
            else:
                hit = any(d.shape is lab.shape and box_overlap(d.box, lab.box) >= 0.5 for d in found)
                c["found"] += hit
                c["found_t"] += hit and lab.shape is Shape.TRIANGLE
    print(f"tuning generator + clocks and check marks, seed {seed}, {frames} frames, hand {hand}: {n_free} mark-free, "
          f"{n_t} with a triangle, {n_marks} with a mark")
    for name, c in counts.items():
        print(f"{name:8s} mark-free frames with a false TRIANGLE {c['false_t']}, with any false mark {c['false_any']}; "
              f"triangles found {c['found_t']} of {n_t}; marks found {c['found']} of {n_marks}")


if __name__ == "__main__":
    main()
