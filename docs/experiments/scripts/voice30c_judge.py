"""Rule voice30c's conditions (round voice30b's rescue, "go" never rescued) on two `bench/voice_bench.py --json` files.

    python docs/experiments/scripts/voice30c_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice30_judge import Bars, judge  # noqa: E402

if __name__ == "__main__":
    sys.exit(judge(Path(sys.argv[1]), Path(sys.argv[2]), Bars(all_points=0.5, neural_points=2.0, one_edit=1.0, asks=0)))
