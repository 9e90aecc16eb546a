"""Round vision36d's rule table: base and variant, per group of runs (vision36_runs.sh's files {base,var}_SPLIT_SEED
[_hand].json), missed and false X / O / TRIANGLE, missed X + TRIANGLE and false-mark frames, summed over the group;
the seeds are round vision36d's unless given (round vision36e: 7095,7096 2777,6373 439,443).
    python3 docs/experiments/scripts/vision36d_rule_table.py OUT [TUNING HELDOUT BLIND]"""

import json
import sys
from pathlib import Path

out = Path(sys.argv[1])
tuning, heldout, blind = (sys.argv[2:5] if len(sys.argv) > 2 else ["7089,7090", "3917,5119", "421,433"])
groups = {
    "S1 tuning exact": [f"tuning_{s}" for s in tuning.split(",")],
    "S1 tuning hand": [f"tuning_{s}_hand" for s in tuning.split(",")],
    "held-out": [f"heldout_{s}" for s in heldout.split(",")],
    "blind": [f"blind_{s}" for s in blind.split(",")],
}
for g, tags in groups.items():
    for c in ("base", "var"):
        files = [out / f"{c}_{t}.json" for t in tags]
        if not all(f.exists() and f.stat().st_size for f in files):
            continue
        rs = [json.loads(f.read_text()) for f in files]
        m = [sum(r["per_class"][k]["missed"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        f = [sum(r["per_class"][k]["false"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        ff = sum(round(r["false_mark_rate"] * r["mark_free_frames"]) for r in rs)
        print(f"{g:16} {c:4} missed X/O/T {m} (X+T {m[0] + m[2]}) false X/O/T {f} (X+T {f[0] + f[2]}) ffr {ff}")
