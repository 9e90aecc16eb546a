"""Rule voice28's conditions (the speech-embedding head refitted) on the four `bench/voice_bench.py --json` files.

    python docs/experiments/scripts/voice28_judge.py A.json B.json C.json D.json

A: the default head with the committed gate (--enrol); B: with the candidate gate (--enrol --enrol-head F);
C: the committed speech-embedding head alone; D: the candidate alone.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice23_judge import figures, verdict  # noqa: E402


def go_walked(path: Path) -> tuple[int, float]:
    """(held-out "go"s walked unasked, "go" heard) in ALL: heard minus those asked and confirmed."""
    row = next(r for r in json.loads(path.read_text()) if r.get("family") == "ALL")
    n_go = row["n"]["commands"] // len(row["by_command"])
    heard = row["by_command"]["go"]
    return round(heard * n_go) - row["of_which_asked_and_confirmed"], heard


def enrolment(path: Path) -> dict[str, dict[str, float]]:
    return next(r["enrolment"] for r in json.loads(path.read_text()) if "enrolment" in r)


def main() -> int:
    a, b, c, d = (Path(p) for p in sys.argv[1:5])
    fb, fc, fd = figures(b), figures(c), figures(d)
    (walked_a, heard_a), (walked_b, heard_b) = go_walked(a), go_walked(b)
    ea, eb = enrolment(a), enrolment(b)
    print(f"go walked unasked A {walked_a}, B {walked_b}; go heard A {heard_a:.3f}, B {heard_b:.3f}")
    for key in fc:
        print(f"{key:28} C {fc[key]:10.3f}  D {fd[key]:10.3f}")
    for part in ("before", "after", "after_on_other_voices"):
        print(f"enrolment {part:24} A {ea[part]}\n{'':34} B {eb[part]}")
    checks = {
        "(1) B: zero direct false walks": fb["walks"] == 0,
        "(2) B: go walked unasked >= A's, go heard >= A's - 0.02": walked_b >= walked_a and heard_b >= heard_a - 0.02,
        "(3) D vs C: eight points >= +3.0, ALL points >=, one-edit <= +1.0, walks <=":
            fd["eight_points"] >= fc["eight_points"] + 3.0 and fd["all_points"] >= fc["all_points"]
            and fd["one_edit"] <= fc["one_edit"] + 1.0 and fd["walks"] <= fc["walks"],
        "(4) enrolment: after acc >= A - 0.03, after other <= A + 2 points, no walk, other voices acc >= A":
            eb["after"]["command_accuracy"] >= ea["after"]["command_accuracy"] - 0.03
            and eb["after"]["oov_accepted"] <= ea["after"]["oov_accepted"] + 0.02
            and eb["after"]["false_walks_direct"] == 0
            and eb["after_on_other_voices"]["command_accuracy"] >= ea["after_on_other_voices"]["command_accuracy"],
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
