import json, sys, glob
from pathlib import Path
d = Path(sys.argv[1]); groups = {"hand": sys.argv[2].split(","), "exact": sys.argv[3].split(",")}
cfgs = sys.argv[4].split(",")
print("config  | group | missed X O T | false X O T | false-mark frames | recall filled-tri | fps/cpu")
for c in cfgs:
    for g, seeds in groups.items():
        rs = [json.loads((d / f"{c}_{s}.json").read_text()) for s in seeds if (d / f"{c}_{s}.json").exists()]
        if len(rs) < len(seeds): continue
        m = [sum(r["per_class"][k]["missed"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        f = [sum(r["per_class"][k]["false"] for r in rs) for k in ("X", "O", "TRIANGLE")]
        ff = sum(round(r["false_mark_rate"] * r["mark_free_frames"]) for r in rs)
        fps = [r["fps_per_cpu_second"] for r in rs]
        tri = [r["recall_by"].get("triangle", {}) for r in rs]
        print(f"{c:7s} | {g:5s} | {m} | {f} | {ff} | {[t.get('filled', {}).get('recall') for t in tri]} | {fps}")
