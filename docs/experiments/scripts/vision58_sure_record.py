"""Round vision58's recording (spent seeds only): every proposed X that round vision56's sure peak keeps (heatmap peak
at `propose_sure` or more, verifier probability under `propose_thresholds`, so kept only because the proposer is sure),
with its peak, the verifier's whole row, its box and whether it is on the frame's X (box overlap 0.5). Today's default
detector, unchanged; `_judged_proposals` and `_proposed` are wrapped only to see what they give.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision58_sure_record.py tuning|blind SEED FRAMES HAND OUT.json
HAND: tuning split only, the share drawn by hand and of varied hands (as the bench's --hand-drawn and --hand-variety)."""
import json
import sys
from pathlib import Path

import cv2

from schemas.messages import Shape
from services.vision import detector as D
from services.vision.verifier import CLASSES

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "bench"))
from vision_bench import _generator  # noqa: E402

cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)
K = CLASSES.index(Shape.X)


class Recording(D.MarkDetector):
    """Today's detector; each X its sure peak alone keeps is written down."""

    def __init__(self) -> None:
        super().__init__()
        self.judged: list[tuple] = []
        self.kept: list[dict] = []

    def _judged_proposals(self, gray, found):  # type: ignore[no-untyped-def]
        self.judged = super()._judged_proposals(gray, found)
        return self.judged

    def _proposed(self, gray, found):  # type: ignore[no-untyped-def]
        out = super()._proposed(gray, found)
        cfg = self.config
        for p, row in self.judged:
            if p.shape is not Shape.X or row[K] >= cfg.propose_thresholds[K]:
                continue
            if any(d.shape is Shape.X and d.box == p.box for d in out):
                self.kept.append({"peak": float(p.score), "row": [float(v) for v in row], "box": list(p.box)})
        return out


def main() -> None:
    split, seed, n, hand, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
    frame_of = _generator(split, seed, hand, hand_drawn=hand) if split == "tuning" else _generator(split, seed)
    det = Recording()
    rows = []
    for i in range(n):
        img, lab, _ = frame_of(ORDER[i % 4])
        det.kept = []
        found = det.detect(img)
        for r in det.kept:
            box = tuple(r["box"])
            r.update(frame=i, truth=lab[0].name if lab else "none", size=max(box[2:]),
                     true=lab is not None and lab[0] is Shape.X and D.box_overlap(box, lab[1]) >= 0.5,
                     reported=any(d.shape is Shape.X and D.box_overlap(d.box, box) >= 0.5 for d in found),
                     other_x=lab is not None and lab[0] is Shape.X and any(
                         d.shape is Shape.X and d.box != box and D.box_overlap(d.box, lab[1]) >= 0.5 for d in found))
            rows.append(r)
    Path(out).write_text(json.dumps(rows))
    print(split, seed, len(rows), "kept by the sure peak alone:", sum(r["true"] for r in rows), "true")


if __name__ == "__main__":
    main()
