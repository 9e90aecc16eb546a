"""Round vision47's recording (tuning frames and round vision47's probe only): every proposed O that the sure peak
alone would keep (heatmap peak >= 0.6, the verifier's O probability 0.75 to under 0.99: round vision42b's PO6), with
`middle_ink` of its box at three middles, labelled true when it is on the frame's O mark (the bench's box rule).
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47_record.py SEED FRAMES HAND OUT.json
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47_record.py probe SEED FRAMES OUT.json
HAND: the share drawn by hand and of varied hands (0.5 or 0). `probe`: vision47_round_probe.py's frames of that seed,
every proposal there false (its control kind, a plain ring, is recorded apart as `kind`)."""

import importlib.util
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
MIDDLES = (0.3, 0.4, 0.5)


class Recording(D.MarkDetector):
    """Today's detector with PO6's sure O; each proposed O kept only by the sure peak is written down."""

    def __init__(self) -> None:
        super().__init__(D.parse_settings(["propose_sure=0,0.6,0", "propose_sure_thresholds=0.01,0.75,0.05"]))
        self.rows: list[dict] = []

    def _judged_proposals(self, gray: np.ndarray, found: list[D.Detection]) -> list[tuple[Proposal, np.ndarray]]:
        judged = super()._judged_proposals(gray, found)
        k = CLASSES.index(Shape.O)
        for p, row in judged:
            if p.shape is Shape.O and p.score >= 0.6 and 0.75 <= row[k] < 0.99:
                f = self._crop_level(p.box)
                g = self._greys.get(f, gray)
                self.rows.append({"peak": p.score, "prob": float(row[k]), "box": list(p.box), "level": f,
                                  "ink": [D.middle_ink(g, D._down(p.box, f), m) for m in MIDDLES]})
        return judged


def main() -> None:
    det = Recording()
    if sys.argv[1] == "probe":
        seed, n, out = int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
        path = Path(__file__).with_name("vision47_round_probe.py")
        spec = importlib.util.spec_from_file_location("probe", path)
        assert spec is not None and spec.loader is not None
        probe = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(probe)
        gen, rng = SceneGenerator(seed=seed), np.random.default_rng(seed)  # the probe's own streams
        for kind in probe.KINDS:
            for i in range(n):
                img, _ = gen.frame(None)
                start = len(det.rows)
                det.detect(probe.draw(rng, kind.split()[0], img.copy()))
                for r in det.rows[start:]:
                    r.update(frame=i, kind=kind, true=False)
    else:
        seed, n, hand, out = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
        gen = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
        for i in range(n):
            img, labels = gen.render(gen.scene(ORDER[i % 4]))
            start = len(det.rows)
            det.detect(img)
            mark = labels[0] if labels else None
            for r in det.rows[start:]:
                r["frame"] = i
                r["true"] = mark is not None and mark.shape is Shape.O and D.box_overlap(tuple(r["box"]), mark.box) >= 0.5
                r["size"] = max(mark.box[2:]) if mark is not None else 0
    Path(out).write_text(json.dumps(det.rows))
    print(len(det.rows), "proposed O kept by the sure peak alone")


if __name__ == "__main__":
    main()
