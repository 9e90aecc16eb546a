"""Rule voice25's conditions on two `bench/voice_bench.py --json` files (figures as rule voice23's judge reads them).

    python docs/experiments/scripts/voice25_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice23_judge import EIGHT, NEURAL, figures  # noqa: E402


def main() -> int:
    c, k = figures(Path(sys.argv[1])), figures(Path(sys.argv[2]))
    for f in (c, k):  # the eleven families no split trains on or that no espeak-ng voice makes: pooled
        heard, cmds = f["eight_heard"] + f["neural_heard"], f["eight_cmds"] + f["neural_cmds"]
        taken, oov = f["eight_taken"] + f["neural_taken"], f["eight_oov"] + f["neural_oov"]
        f["eleven_points"] = 100 * (heard / cmds - taken / oov)
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) eleven families points >= control + 2.0": k["eleven_points"] >= c["eleven_points"] + 2.0,
        "(3) ALL points >= control - 1.0": k["all_points"] >= c["all_points"] - 1.0,
        "(4) eight families points >= control - 1.0": k["eight_points"] >= c["eight_points"] - 1.0,
        "(5) neural points >= control - 1.0": k["neural_points"] >= c["neural_points"] - 1.0,
        "(6) one-edit accepted <= control + 1.0": k["one_edit"] <= c["one_edit"] + 1.0,
        "(7) false asks <= control + 10": k["asks"] <= c["asks"] + 10,
        "(8) RTF <= 0.1": k["rtf"] <= 0.1,
    }
    for name, ok in checks.items():
        print(f"{'holds' if ok else 'FAILS':6} {name}")
    passed = all(checks.values())
    print("passes" if passed else "does NOT pass")
    return 0 if passed else 1


if __name__ == "__main__":
    assert len(EIGHT) == 8 and len(NEURAL) == 3
    raise SystemExit(main())
