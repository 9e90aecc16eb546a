"""voice8: the proxy table from voice8-*.log (not part of the repo), and the fixed decision rule fmask vs dup."""
import json
import sys

ROT = ("flite:kal16", "flite:awb", "festival:ked")


def rows(v):
    out = {}
    for name in (f"/work/notes/runs/voice8-{v}.log",):
        try:
            for line in open(name):
                if '"drop"' in line:
                    r = json.loads(line)
                    if r["variant"] == v.split("-")[-1]:
                        out[r["drop"]] = r
        except FileNotFoundError:
            pass
    return out


def summary(by, key="left_out"):
    done = [by[d] for d in ROT if d in by and key in by[d]]
    n = len(done)
    if not n:
        return None
    return {"n": n, "acc": sum(r[key]["command_accuracy"] for r in done) / n,
            "oth": 100 * sum(r[key]["other_accepted"] for r in done) / n,
            "fa": sum(r[key]["false_go_ask"] for r in done), "fw": sum(r[key]["false_go_walk"] for r in done),
            "fw_any": any(r[key]["false_go_walk"] > 0 for r in done), "drops": [r["drop"] for r in done]}


table = {}
for v in sys.argv[1:] or ("base", "dup", "fmask"):
    by = rows(v)
    table[v] = by
    for key in ("left_out", "tight"):
        s = summary(by, key)
        if not s:
            continue
        cells = []
        for d in ROT:
            if d in by and key in by[d]:
                lo = by[d][key]
                cells.append(f"{lo['command_accuracy']:.3f} / {100 * lo['other_accepted']:.1f} % / {lo['false_go_walk']:g}")
            else:
                cells.append("-")
        extra = ""
        if key == "left_out":
            done = [by[d] for d in ROT if d in by]
            ta = [r["tune"]["command_accuracy"] for r in done]
            to = [100 * r["tune"]["other_accepted"] for r in done]
            tw = sum(r["all"]["false_go_walk"] - r["left_out"]["false_go_walk"] for r in done)
            extra = (f" {min(ta):.2f}-{max(ta):.2f} acc, {min(to):.1f}-{max(to):.1f} %; other tune rows false walks {tw:g} |"
                     f" fit s {[r['fit_s'] for r in done]}, train rows {[r['train_rows'] for r in done]}")
        print(f"| {v}{' (tight budget)' if key == 'tight' else ''} (n={s['n']}) | " + " | ".join(cells)
              + f" | **{s['acc']:.3f}** | **{s['oth']:.1f} %** | {s['fa']:g} / {s['fw']:g} |{extra}")

# decision rule (fixed before any result): on the rotations both have, fmask vs dup
for pre in ("", "rep-"):
  common = [d for d in ROT if d in table.get(pre + "dup", {}) and d in table.get(pre + "fmask", {})]
  if common:
    a = summary({d: table[pre + "dup"][d] for d in common})
    b = summary({d: table[pre + "fmask"][d] for d in common})
    dacc, doth = 100 * (b["acc"] - a["acc"]), b["oth"] - a["oth"]
    ok = dacc >= 1.5 and doth <= 0.5 and not b["fw_any"]
    print(f"{pre}rule on {common}: fmask - dup accuracy {dacc:+.1f} points (need >= +1.5), non-commands {doth:+.1f} points "
          f"(need <= +0.5), fmask false walks on left-out {b['fw']:g} (need 0) -> {'TAKE' if ok else 'DROP'}")
