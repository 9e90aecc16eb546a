"""Rule voice37's conditions (and round voice37b's, the same) on the four JSON files of its held-out runs.

    python docs/experiments/scripts/voice37_judge.py A_CONTROL.json A_CANDIDATE.json B_CONTROL.json B_CANDIDATE.json

A: `bench/voice_levels.py --paths stream` (rows by peak level; 12.0 is 12 dB past full scale); B: `bench/voice_walking.py
--vad silero` (rows by speech-to-noise ratio, and the noise alone).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def levels(path: Path) -> dict[float, dict]:
    return {r["peak_dbfs"]: r for r in json.loads(path.read_text())["rows"] if r["path"] == "stream"}


def main() -> int:
    ac, ak = levels(Path(sys.argv[1])), levels(Path(sys.argv[2]))
    bc, bk = (json.loads(Path(p).read_text()) for p in sys.argv[3:5])
    pts = 100.0
    print(f"{'A level':>10} {'control cmd / other / p50':>28} {'candidate':>28}")
    for peak in ac:
        c, k = ac[peak], ak[peak]
        print(f"{peak:10.0f} {c['command_accuracy']:10.3f} {c['oov_accepted']:7.3f} "
              f"{c['end_of_speech_to_segment_ms_p50_p90'][0]:8.1f} {k['command_accuracy']:10.3f} "
              f"{k['oov_accepted']:7.3f} {k['end_of_speech_to_segment_ms_p50_p90'][0]:8.1f}")
    brc = {str(r["snr_db"]): r for r in bc["ratios"]}
    brk = {str(r["snr_db"]): r for r in bk["ratios"]}
    for snr in brc:
        c, k = brc[snr], brk[snr]
        print(f"B {snr:>8} {c['command_accuracy']:10.3f} {c['oov_accepted']:7.3f} {k['command_accuracy']:19.3f} "
              f"{k['oov_accepted']:7.3f}")
    nc, nk = bc["noise_only"][0], bk["noise_only"][0]
    print(f"B noise alone: control {nc['segments']} segments {nc['commands_heard']}, "
          f"candidate {nk['segments']} segments {nk['commands_heard']}")
    trained = [-32.0, -26.0, -14.0, -3.0, 12.0]
    checks = {
        "(1) no false walk": all(r["false_walks"] == 0 for r in [*ak.values(), *brk.values()]),
        "(2) -44 and -38: commands >= control + 15 points": all(
            ak[p]["command_accuracy"] * pts >= ac[p]["command_accuracy"] * pts + 15 for p in (-44.0, -38.0)),
        "(3a) trained levels and clipped: commands >= control - 2.5 points each": all(
            ak[p]["command_accuracy"] * pts >= ac[p]["command_accuracy"] * pts - 2.5 for p in trained),
        "(3b) their mean >= control's - 1.0": sum(ak[p]["command_accuracy"] for p in trained) / len(trained) * pts
        >= sum(ac[p]["command_accuracy"] for p in trained) / len(trained) * pts - 1.0,
        "(4a) other words <= control + 2.0 points, trained levels and clipped": all(
            ak[p]["oov_accepted"] * pts <= ac[p]["oov_accepted"] * pts + 2.0 for p in trained),
        "(4b) other words <= 12 % at -44 and -38": all(ak[p]["oov_accepted"] <= 0.12 for p in (-44.0, -38.0)),
        "(5a) B: commands >= control - 2.5 points, other words <= control + 2.0": all(
            brk[s]["command_accuracy"] * pts >= brc[s]["command_accuracy"] * pts - 2.5
            and brk[s]["oov_accepted"] * pts <= brc[s]["oov_accepted"] * pts + 2.0 for s in brc),
        "(5b) B noise alone: no command, segments <= control + 2": not nk["commands_heard"]
        and nk["segments"] <= nc["segments"] + 2,
        "(6) p50 at -26 and -3 <= control + 10 ms": all(
            ak[p]["end_of_speech_to_segment_ms_p50_p90"][0] <= ac[p]["end_of_speech_to_segment_ms_p50_p90"][0] + 10
            for p in (-26.0, -3.0)),
    }
    for name, ok in checks.items():
        print(f"{'holds' if ok else 'FAILS':6} {name}")
    passed = all(checks.values())
    print("passes" if passed else "does NOT pass")
    return 0 if passed else 1


if __name__ == "__main__":
    raise SystemExit(main())
