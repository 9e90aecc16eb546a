"""Round vision39c: for every doubted triangle (shape and context tests passed, verifier and second network refused): is it on the
frame's true triangle, was it found anyway, and the verifier's TRIANGLE probability on the proposal-style crop
(coarsest level >= 48 px) with no claim and with the TRIANGLE claim; whether a proposal overlapped it. As run, on a worktree with the `propose_doubted` option (removed after the probe):
    PYTHONPATH=$W .venv/bin/python docs/experiments/scripts/vision39c_doubted.py SEED HAND FRAMES"""
import sys, cv2, numpy as np, collections, json
from services.vision.detector import MarkDetector, parse_settings, box_overlap, to_gray
from services.vision.verifier import claim, CLASSES
from services.vision.synthetic import SceneGenerator, Variation
from bench.vision_stages import ORDER
from schemas.messages import Shape
cv2.setNumThreads(1)
det = MarkDetector(parse_settings("propose_doubted=0.99"))  # records _doubted; keeps (almost) nothing extra
k = CLASSES.index(Shape.TRIANGLE)
seed, hand, n = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
g = SceneGenerator(seed=seed, variation=Variation(hand_variety=hand, hand_drawn=hand))
for i in range(n):
    img, labels = g.render(g.scene(ORDER[i % 4]))
    found = det.detect(img)
    if not det._doubted:
        continue
    gray = to_gray(img)
    props = det.proposer.propose(gray, det.config.propose)
    lab = labels[0] if labels else None
    for box in det._doubted:
        true = lab is not None and lab.shape is Shape.TRIANGLE and box_overlap(box, lab.box) >= 0.5
        on_other = lab is not None and not true and box_overlap(box, lab.box) >= 0.5
        got = lab is not None and any(d.shape is lab.shape and box_overlap(d.box, lab.box) >= 0.5 for d in found)
        patch = det.proposal_crops(gray, box)[None]
        p_none = float(det.verifier.probabilities(patch, claim(None)[None])[0][k])
        p_tri = float(det.verifier.probabilities(patch, claim(Shape.TRIANGLE)[None])[0][k])
        prop = max((p.score for p in props if p.shape is Shape.TRIANGLE and box_overlap(p.box, box) >= 0.5), default=0.0)
        print(json.dumps({"frame": i, "true": true, "other_mark": on_other, "found": got, "p_none": round(p_none, 3),
                          "p_tri": round(p_tri, 3), "proposal": round(prop, 2), "box": list(box),
                          "filled": bool(lab is not None and true and max(lab.box[2:]) > 0)}))
