"""Rule voice30's conditions (Whisper's decoder rescues commands the head missed) on two `bench/voice_bench.py --json`
files.

    python docs/experiments/scripts/voice30_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import figures, verdict  # noqa: E402
from voice27_judge import latency_p50  # noqa: E402


def noise(path: Path) -> float:
    return max(float(r["noise_accepted"]) for r in json.loads(path.read_text()) if "family" in r)


def main() -> int:
    control, candidate = Path(sys.argv[1]), Path(sys.argv[2])
    c, k = figures(control), figures(candidate)
    for d, path in ((c, control), (k, candidate)):
        d["latency_p50"], d["noise"] = latency_p50(path), noise(path)
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) ALL points >= control + 2.0": k["all_points"] >= c["all_points"] + 2.0,
        "(3) eight families points >= control": k["eight_points"] >= c["eight_points"],
        "(4) neural points >= control - 1.0": k["neural_points"] >= c["neural_points"] - 1.0,
        "(5) one-edit accepted <= control + 1.5 points": k["one_edit"] <= c["one_edit"] + 1.5,
        "(6) false asks <= control + 20": k["asks"] <= c["asks"] + 20,
        "(7) noise accepted <= control": k["noise"] <= c["noise"],
        "(8) RTF <= 0.1, latency p50 <= control + 10 ms": k["rtf"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 10,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
