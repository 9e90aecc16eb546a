"""Round vision47's look at a diagnostic blind seed (looked at, so never used for a decision): the proposed O that the
sure peak alone keeps (vision47_record.py's PO6), true or false by the bench's box rule, each with `middle_ink` at three
middles and a crop (twice its box) written as a PNG, so that what the blind generator's false O are can be seen.
    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision47_blind_look.py SEED FRAMES OUT_DIR"""

import importlib.util
import json
import sys
from pathlib import Path

import cv2

from schemas.messages import Shape
from services.vision import detector as D
from services.vision.blind import BlindGenerator

cv2.setNumThreads(1)
ORDER = (Shape.X, Shape.O, Shape.TRIANGLE, None)


def main() -> None:
    seed, n, out = int(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3])
    out.mkdir(parents=True, exist_ok=True)
    spec = importlib.util.spec_from_file_location("record", Path(__file__).with_name("vision47_record.py"))
    assert spec is not None and spec.loader is not None
    record = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(record)
    det = record.Recording()
    gen = BlindGenerator(seed=seed)
    for i in range(n):
        truth = ORDER[i % 4]
        img, lab = gen.frame(truth)
        start = len(det.rows)
        det.detect(img)
        for j, r in enumerate(det.rows[start:]):
            r["frame"] = i
            r["truth"] = truth.name if truth else "none"
            r["true"] = lab is not None and lab.shape is Shape.O and D.box_overlap(tuple(r["box"]), lab.box) >= 0.5
            x, y, w, h = r["box"]
            crop = img[max(0, y - h // 2) : y + h + h // 2, max(0, x - w // 2) : x + w + w // 2]
            name = f"{'true' if r['true'] else 'false'}_{i:04d}_{j}_ink{r['ink'][1]:.2f}.png"
            if crop.size:
                cv2.imwrite(str(out / name), cv2.resize(crop, (160, int(160 * crop.shape[0] / max(1, crop.shape[1])))))
    (out / "rows.json").write_text(json.dumps(det.rows))
    print(sum(r["true"] for r in det.rows), "true and", sum(not r["true"] for r in det.rows), "false proposed O kept by the"
          " sure peak alone")


if __name__ == "__main__":
    main()
