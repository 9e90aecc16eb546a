"""Round vision36d's probe table: per config, missed and false X / O / TRIANGLE and false-mark frames, summed over the
tuning seeds drawn half by hand (7085, 7086) and exact (7087, 7088), or those given (round vision37: 7091,7092 and
7093,7094).
    python3 docs/experiments/scripts/vision36d_probe_table.py OUT base,P25,P35 [HAND EXACT]"""

import json
import sys
from pathlib import Path

out, configs = Path(sys.argv[1]), sys.argv[2].split(",")
hand, exact = sys.argv[3:5] if len(sys.argv) > 3 else ("7085,7086", "7087,7088")
groups = {"hand": hand.split(","), "exact": exact.split(",")}
for c in configs:
    row = []
    for g, seeds in groups.items():
        files = [out / f"{c}_{s}.json" for s in seeds]
        if not all(f.exists() and f.stat().st_size for f in files):
            row.append(f"{g}: -")
            continue
        rs = [json.loads(f.read_text()) for f in files]
        m = [sum(r["per_class"][k]["missed"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        f = [sum(r["per_class"][k]["false"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        ff = sum(round(r["false_mark_rate"] * r["mark_free_frames"]) for r in rs)
        row.append(f"{g}: missed {m} false {f} ffr {ff}")
    print(c, " | ".join(row))
