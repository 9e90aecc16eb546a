"""Round vision42's recording (tuning frames and the arrow probe only): every proposal the detector shows the verifier,
with its heatmap peak and the verifier's probability for the proposed shape, labelled true when it is on the frame's
mark with the right shape (the bench's box rule). The detector is today's, unchanged; `_judged_proposals` is wrapped
only to see what it gives.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision42_proposals.py SEED FRAMES HAND OUT.json
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision42_proposals.py arrows OUT.json
HAND: the share drawn by hand and of varied hands (0.5 for 7132, 0 for 7133). `arrows`: the arrow probe's 750 frames
(vision34_triclutter_probe.py, seed 7), every proposal there false. Each record: shape, peak, prob, box, frame, true,
mark_found (the detector found the frame's mark), size (the mark's longer side; 0 on a mark-free frame)."""

import json
import sys
from pathlib import Path

import cv2
import numpy as np

from schemas.messages import Shape
from services.vision import detector as D
from services.vision.proposer import Proposal
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import CLASSES

cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)


class Recording(D.MarkDetector):
    """Today's detector; each proposal the verifier judges is also written down with its probability."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[dict] = []

    def _judged_proposals(self, gray: np.ndarray, found: list[D.Detection]) -> list[tuple[Proposal, np.ndarray]]:
        judged = super()._judged_proposals(gray, found)
        for p, row in judged:
            self.rows.append({"shape": p.shape.name, "peak": p.score, "prob": float(row[CLASSES.index(p.shape)]),
                              "box": list(p.box)})
        return judged


def main() -> None:
    det = Recording()
    if sys.argv[1] == "arrows":
        probe = Path(__file__).with_name("vision34_triclutter_probe.py").read_text()
        ns: dict = {}
        setup = probe.split("for kind in (")[0].replace("det = MarkDetector(parse_settings(sys.argv[1:]))", "")
        exec(setup, ns)  # its drawing and its random streams, seed 7
        for kind in ("play button", "warning sign", "roof", "delta text", "arrow"):
            for i in range(150):
                img, _ = ns["gen"].frame(None)
                start = len(det.rows)
                det.detect(ns["draw"](kind, img.copy()))
                for r in det.rows[start:]:
                    r.update(frame=i, kind=kind, true=False, mark_found=False, size=0)
        out = sys.argv[2]
    else:
        seed, n, hand, out = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
        gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
        for i in range(n):
            img, labels = gen.render(gen.scene(ORDER[i % 4]))
            start = len(det.rows)
            dets = det.detect(img)
            mark = labels[0] if labels else None
            for r in det.rows[start:]:
                r["frame"] = i
                r["true"] = mark is not None and r["shape"] == mark.shape.name and D.box_overlap(tuple(r["box"]), mark.box) >= 0.5
                r["mark_found"] = mark is not None and any(
                    d.shape is mark.shape and D.box_overlap(d.box, mark.box) >= 0.5 for d in dets
                )
                r["size"] = max(mark.box[2:]) if mark is not None else 0
    Path(out).write_text(json.dumps(det.rows))
    print(len(det.rows), "proposals")


if __name__ == "__main__":
    main()
