"""Rule voice29's conditions on two `bench/voice_bench.py --json` files (the figures are rule voice23's judge's).

    python docs/experiments/scripts/voice29_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import sys
from pathlib import Path

from voice23_judge import figures, verdict


def main() -> int:
    c, k = figures(Path(sys.argv[1])), figures(Path(sys.argv[2]))
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) eight families points >= control + 2.0": k["eight_points"] >= c["eight_points"] + 2.0,
        "(3) ALL points >= control - 1.0": k["all_points"] >= c["all_points"] - 1.0,
        "(4) neural points >= control - 2.0": k["neural_points"] >= c["neural_points"] - 2.0,
        "(5) one-edit accepted <= control + 1.0": k["one_edit"] <= c["one_edit"] + 1.0,
        "(6) false asks <= control + 10": k["asks"] <= c["asks"] + 10,
        "(7) RTF <= 0.1": k["rtf"] <= 0.1,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
