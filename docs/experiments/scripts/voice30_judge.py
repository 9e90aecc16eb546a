"""Rule voice30's conditions (Whisper's decoder rescues commands the head missed) on two `bench/voice_bench.py --json`
files.

    python docs/experiments/scripts/voice30_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import figures, verdict  # noqa: E402
from voice27_judge import latency_p50  # noqa: E402


def noise(path: Path) -> float:
    return max(float(r["noise_accepted"]) for r in json.loads(path.read_text()) if "family" in r)


@dataclass(frozen=True)
class Bars:
    """What the candidate must reach against the control (rule voice30's; rule voice30b's differ)."""

    all_points: float = 2.0
    neural_points: float = -1.0
    one_edit: float = 1.5
    asks: int = 20


def judge(control: Path, candidate: Path, bars: Bars) -> int:
    c, k = figures(control), figures(candidate)
    for d, path in ((c, control), (k, candidate)):
        d["latency_p50"], d["noise"] = latency_p50(path), noise(path)
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        f"(2) ALL points >= control + {bars.all_points}": k["all_points"] >= c["all_points"] + bars.all_points,
        "(3) eight families points >= control": k["eight_points"] >= c["eight_points"],
        f"(4) neural points >= control {bars.neural_points:+}": k["neural_points"] >= c["neural_points"] + bars.neural_points,
        f"(5) one-edit accepted <= control + {bars.one_edit} points": k["one_edit"] <= c["one_edit"] + bars.one_edit,
        f"(6) false asks <= control + {bars.asks}": k["asks"] <= c["asks"] + bars.asks,
        "(7) noise accepted <= control": k["noise"] <= c["noise"],
        "(8) RTF <= 0.1, latency p50 <= control + 10 ms": k["rtf"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 10,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(judge(Path(sys.argv[1]), Path(sys.argv[2]), Bars()))
