"""Compare split variants on the SAME tuning frames in one process (tuning only).
usage: sweep.py SEEDS FRAMES 'name:k=v,k=v;name2:...' [fingers]"""
from __future__ import annotations
import json, sys, time
from collections import defaultdict
import cv2
from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector, box_overlap
from services.vision.synthetic import SceneGenerator, Variation
from services.vision.verifier import Verifier
CL = (Shape.X, Shape.O, Shape.TRIANGLE, None)

def variants(spec):
    v = Verifier.load(); out = {}
    for item in spec.split(";"):
        name, _, kv = item.partition(":")
        cfg = {}
        for p in [p for p in kv.split(",") if p]:
            k, val = p.split("=")
            cfg[k] = val.replace("+", ",") if k == "split" else tuple(int(a) for a in val.split("+")) if k == "split_levels" else float(val) if "." in val else int(val)
        out[name] = MarkDetector(DetectorConfig(**cfg), verifier=v)
    return out

def main(seeds, frames, spec, mode):
    cv2.setNumThreads(1)
    dets = variants(spec)
    st = {n: dict(tp=defaultdict(int), fp=defaultdict(int), n=defaultdict(int), fm=0, cpu=0.0, fin=[0, 0], fpk=defaultdict(list)) for n in dets}
    empty = 0
    var = Variation(fingers=1.0, finger_over=0.5) if mode == "fingers" else Variation()
    for seed in seeds:
        g = SceneGenerator(seed=seed, variation=var)
        for i in range(frames):
            sc = g.scene(CL[i % 4]); img, labels = g.render(sc)
            lab = (labels[0].shape, labels[0].box) if labels else None
            empty += lab is None
            for name, d in dets.items():
                s = st[name]
                c0 = time.process_time(); found = d.detect(img); s["cpu"] += time.process_time() - c0
                hit = False
                for f in found:
                    if lab is not None and not hit and f.shape == lab[0] and box_overlap(f.box, lab[1]) >= 0.5:
                        hit = True; s["tp"][f.shape.value] += 1
                    else:
                        s["fp"][f.shape.value] += 1; s["fpk"][f.shape.value].append(f"{seed}/{i}")
                if lab is None:
                    s["fm"] += bool(found)
                else:
                    s["n"][lab[0].value] += 1
                    if sc.fingers:
                        s["fin"][0] += hit; s["fin"][1] += 1
    total = len(seeds) * frames
    for name, s in st.items():
        row = {}
        for k in ("X", "O", "TRIANGLE"):
            tp, fp, n = s["tp"][k], s["fp"][k], s["n"][k]
            row[k] = f"{tp/(tp+fp) if tp+fp else 0:.3f}/{tp/n:.3f} fp{fp} miss{n-tp}"
        print(json.dumps({"variant": name, "seeds": seeds, "mode": mode, **row, "fm": f"{s['fm']}/{empty}",
                          "finger": f"{s['fin'][0]/max(1,s['fin'][1]):.3f} n{s['fin'][1]}",
                          "fps_cpu": round(total / s["cpu"], 1), "fp_at": dict(s["fpk"])}), flush=True)

if __name__ == "__main__":
    main([int(x) for x in sys.argv[1].split(",")], int(sys.argv[2]), sys.argv[3], sys.argv[4] if len(sys.argv) > 4 else "")
