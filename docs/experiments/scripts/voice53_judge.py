"""Rule voice53's conditions for candidate C1 (the refitted speech-embedding head as the walk gate and the enrolment
base) on two `bench/voice_bench.py --enrol --json` files; C2 (the veto) is judged by voice27_judge.py.

    python docs/experiments/scripts/voice53_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import EIGHT, NEURAL, figures, verdict  # noqa: E402


def extra(path: Path) -> dict[str, float]:
    rows = json.loads(path.read_text())
    fam = {r["family"]: r for r in rows if "family" in r}
    enrol = next(r["enrolment"] for r in rows if "enrolment" in r)
    return {
        "go_walked": sum(fam[f]["go_walked"] for f in ("ALL", *EIGHT, *NEURAL)),
        "enrol_after_accuracy": enrol["after"]["command_accuracy"],
        "enrol_after_oov": 100 * enrol["after"]["oov_accepted"],
        "enrol_other_voices_accuracy": enrol["after_on_other_voices"]["command_accuracy"],
    }


def main() -> int:
    control, candidate = Path(sys.argv[1]), Path(sys.argv[2])
    c, k = figures(control) | extra(control), figures(candidate) | extra(candidate)
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    gains = (k["go_walked"] >= c["go_walked"] + 3 or k["enrol_after_accuracy"] >= c["enrol_after_accuracy"] + 0.03
             or k["enrol_after_oov"] <= c["enrol_after_oov"] - 3.0)
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) ALL accuracy >= control - 0.005; eight and neural heard >= control - 2":
            k["all_accuracy"] >= c["all_accuracy"] - 0.005 and k["eight_heard"] >= c["eight_heard"] - 2
            and k["neural_heard"] >= c["neural_heard"] - 2,
        "(3) false asks <= control + 5": k["asks"] <= c["asks"] + 5,
        "(4) a gain: go walked +3, or enrolled accuracy +0.03, or enrolled other words -3.0 points": gains,
        "(5) enrolled accuracy >= control - 0.03, other words <= control + 2.0, other voices >= control - 0.03":
            k["enrol_after_accuracy"] >= c["enrol_after_accuracy"] - 0.03
            and k["enrol_after_oov"] <= c["enrol_after_oov"] + 2.0
            and k["enrol_other_voices_accuracy"] >= c["enrol_other_voices_accuracy"] - 0.03,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
