"""voice7: the proxy table from the voice7-proxy-*.log files (not part of the repo)."""
import json, sys
ROT = ("flite:kal16", "flite:awb", "festival:ked")
for v in sys.argv[1:] or ("base", "cmvn", "fmask", "tilt"):
    try:
        rows = [json.loads(l) for l in open(f"/work/notes/runs/voice7-proxy-{v}.log") if '"drop"' in l]
    except FileNotFoundError:
        continue
    by = {r["drop"]: r for r in rows}
    cells = []
    for d in ROT:
        if d in by:
            lo = by[d]["left_out"]
            cells.append(f"{lo['command_accuracy']:.3f} / {100*lo['other_accepted']:.1f} %")
        else:
            cells.append("-")
    done = [by[d] for d in ROT if d in by]
    n = len(done)
    if not n:
        continue
    acc = sum(r["left_out"]["command_accuracy"] for r in done) / n
    oth = sum(r["left_out"]["other_accepted"] for r in done) / n
    fa = sum(r["left_out"]["false_go_ask"] for r in done)
    fw = sum(r["left_out"]["false_go_walk"] for r in done)
    ta = [r["tune"]["command_accuracy"] for r in done]
    to = [100 * r["tune"]["other_accepted"] for r in done]
    tw = sum(r["all"]["false_go_walk"] - r["left_out"]["false_go_walk"] for r in done)
    tfa = sum(r["all"]["false_go_ask"] - r["left_out"]["false_go_ask"] for r in done)
    print(f"| {v} (n={n}) | " + " | ".join(cells) + f" | **{acc:.3f}** | **{100*oth:.1f} %** | {fa:g} / {fw:g} | "
          f"{min(ta):.2f}-{max(ta):.2f} acc, {min(to):.1f}-{max(to):.1f} %; other tune rows: false go asked {tfa:g}, walked {tw:g} |"
          f" fit s {[r['s'] for r in done]}, train rows {[r['train_rows'] for r in done]}")
