"""Rule voice27's conditions (the agreement veto) on two `bench/voice_bench.py --json` files.

    python docs/experiments/scripts/voice27_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import figures, verdict  # noqa: E402


def latency_p50(path: Path) -> float:
    rows = [r for r in json.loads(path.read_text()) if r.get("family") == "ALL"]
    return float(rows[0]["stream_latency"]["p50_ms"])


def main() -> int:
    control, candidate = Path(sys.argv[1]), Path(sys.argv[2])
    c, k = figures(control), figures(candidate)
    c["latency_p50"], k["latency_p50"] = latency_p50(control), latency_p50(candidate)
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) ALL points >= control + 1.0": k["all_points"] >= c["all_points"] + 1.0,
        "(3) ALL other words accepted <= control - 2.0 points": 100 * k["all_oov"] <= 100 * c["all_oov"] - 2.0,
        "(4) eight families points >= control - 1.0": k["eight_points"] >= c["eight_points"] - 1.0,
        "(5) neural points >= control - 1.0": k["neural_points"] >= c["neural_points"] - 1.0,
        "(6) one-edit accepted <= control": k["one_edit"] <= c["one_edit"],
        "(7) ALL go heard >= control - 0.05": k["go_heard"] >= c["go_heard"] - 0.05,
        "(8) RTF <= 0.1, latency p50 <= control + 20 ms": k["rtf"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 20,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
