"""Round vision60's look (stop 106; tuning frames and spent blind seeds only; nothing in the detector came of it): do
the filled triangles the detector misses lie on a whole card or sheet that a wider look than the verifier's could
find? Needs the code of commit 890671f (`services/vision/sheet.py`, `DetectorConfig.filled_card_reach` and the tuning
bench's `--sheets`), reverted in the commit after it:

    git worktree add /tmp/wt60 890671f && ln -s $PWD/.venv /tmp/wt60/.venv
    cp docs/experiments/scripts/vision60_sheet_look.py /tmp/wt60/ && cd /tmp/wt60
    PYTHONPATH=. .venv/bin/python vision60_sheet_look.py SPLIT SEED FRAMES [sheets]
    PYTHONPATH=. .venv/bin/python bench/vision_bench.py --split SPLIT --seed SEED [--sheets] \
        [--set filled_card_reach=4] --json

For every filled triangle the default detector misses, prints how often `sheet.whole_sheet` on its true box finds a
whole sheet within 4 and within 30 times its size (30: the whole frame), or the first test that failed. Stop 106 ran
tuning 6 with `sheets` and blind 853 and 863 (2,000 frames each); the vision README reports it.
"""

import collections
import sys

sys.path.insert(0, "bench")
import vision_bench as vb  # noqa: E402
from services.vision.sheet import whole_sheet  # type: ignore[import-not-found]  # noqa: E402

from schemas.messages import Shape  # noqa: E402
from services.vision.detector import MarkDetector, box_overlap, to_gray  # noqa: E402


def main() -> None:
    split, seed, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    frame_of = vb._generator(split, seed, sheets=len(sys.argv) > 4)
    det = MarkDetector()
    why: collections.Counter[tuple[str, str]] = collections.Counter()
    for i in range(n):
        truth = vb.CLASSES[i % 4]
        img, label, meta = frame_of(truth)
        if truth is not Shape.TRIANGLE or meta.get("triangle") != "filled":
            continue
        if any(d.shape is Shape.TRIANGLE and box_overlap(d.box, label[1]) >= 0.5 for d in det.detect(img)):
            continue
        g = to_gray(img)
        why[(whole_sheet(g, label[1], 4), whole_sheet(g, label[1], 30))] += 1
    print(f"{split} {seed}, {n} frames: {sum(why.values())} missed filled triangles; (reach 4, reach 30): count")
    for k, v in why.most_common():
        print(f"  {k}: {v}")


if __name__ == "__main__":
    main()
