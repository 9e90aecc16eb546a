"""Round vision29's judge: reads the bench's JSON runs and prints every condition of vision29_rule.txt.

    python docs/experiments/scripts/vision29_judge.py RUNS_DIR [TUNING TUNING [HELDOUT HELDOUT BLIND BLIND]]
    # vision29: 7026 7027 (8181 9292 119 120 by default); 29b: 7028 7029; 29c: 7030 7031 2323 5252 121 122

RUNS_DIR holds {base,variant}_{tuning7026,tuning7027,heldout8181,heldout9292,blind119,blind120}.json
(`bench/vision_bench.py --json`); a missing pair is reported as not run.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

SHAPES = ("X", "O", "TRIANGLE")


def load(runs: Path, who: str, names: tuple[str, ...]) -> list[dict] | None:
    files = [runs / f"{who}_{n}.json" for n in names]
    return [json.loads(f.read_text()) for f in files] if all(f.exists() for f in files) else None


def total(results: list[dict], field: str, shapes: tuple[str, ...]) -> int:
    return sum(r["per_class"][s][field] for r in results for s in shapes)


def false_frames(results: list[dict]) -> int:
    return sum(round(r["false_mark_rate"] * r["mark_free_frames"]) for r in results)


def check(name: str, value: float, limit: float) -> bool:
    ok = value <= limit
    print(f"  {name}: {value:g} (<= {limit:g}) {'held' if ok else 'FAILED'}")
    return ok


def main(runs: Path, tuning: tuple[str, ...] = ("7026", "7027"), heldout: tuple[str, ...] = ("8181", "9292"),
         blind: tuple[str, ...] = ("119", "120")) -> int:
    verdicts: list[bool] = []
    for label, names in ((f"S1 tuning {' + '.join(tuning)}", tuple(f"tuning{s}" for s in tuning)),
                         (f"held-out {' + '.join(heldout)}", tuple(f"heldout{s}" for s in heldout)),
                         (f"blind {' + '.join(blind)} (reported)", tuple(f"blind{s}" for s in blind))):
        base, var = load(runs, "base", names), load(runs, "variant", names)
        if base is None or var is None:
            print(f"{label}: not run")
            continue
        print(label)
        for b, v in zip(base, var, strict=True):
            row = ", ".join(f"{s} {b['per_class'][s]['precision']} / {b['per_class'][s]['recall']} -> "
                            f"{v['per_class'][s]['precision']} / {v['per_class'][s]['recall']}" for s in SHAPES)
            print(f"  seed {b['seed']}: {row}; false-mark frames {false_frames([b])} -> {false_frames([v])}; "
                  f"{b['fps_per_cpu_second']} -> {v['fps_per_cpu_second']} frames per CPU-second")
        mxt = (total(base, "missed", ("X", "TRIANGLE")), total(var, "missed", ("X", "TRIANGLE")))
        mo = (total(base, "missed", ("O",)), total(var, "missed", ("O",)))
        fxt = (total(base, "false", ("X", "TRIANGLE")), total(var, "false", ("X", "TRIANGLE")))
        fo = (total(base, "false", ("O",)), total(var, "false", ("O",)))
        fall = (total(base, "false", SHAPES), total(var, "false", SHAPES))
        ff = (false_frames(base), false_frames(var))
        print(f"  missed X + TRIANGLE {mxt[0]} -> {mxt[1]}, missed O {mo[0]} -> {mo[1]}, false X + TRIANGLE "
              f"{fxt[0]} -> {fxt[1]}, false O {fo[0]} -> {fo[1]}, false-mark frames {ff[0]} -> {ff[1]}")
        if label.startswith("S1"):
            verdicts += [check("false marks", fall[1], fall[0] + 3), check("missed X + TRIANGLE", mxt[1], mxt[0] + 10),
                         check("missed O", mo[1], mo[0] + 10)]
        elif label.startswith("held-out"):
            verdicts += [check("(a) missed X + TRIANGLE + O", mxt[1] + mo[1], mxt[0] + mo[0] - 25),
                         check("(a) missed X + TRIANGLE", mxt[1], mxt[0]), check("(a) missed O", mo[1], mo[0] + 5),
                         check("(c) false X + TRIANGLE", fxt[1], fxt[0] + 10), check("(d) false O", fo[1], fo[0] + 2),
                         check("(e) false-mark frames", ff[1], ff[0] + 5)]
    print("(T3-T5 and (f) are separate runs; see the rule.)")
    print("all conditions above held" if verdicts and all(verdicts) else "NOT all held (or not run)")
    return 0


if __name__ == "__main__":
    seeds = sys.argv[2:]
    if len(seeds) not in (0, 2, 6):
        sys.exit(__doc__)
    sys.exit(main(Path(sys.argv[1]), *(tuple(seeds[k : k + 2]) for k in range(0, len(seeds), 2))))
