"""Rule voice37's conditions (and round voice37b's, the same) on the four JSON files of its held-out runs; with
`--rule 37c`, round voice37c's (its A runs with `--paths stream,file`).

    python docs/experiments/scripts/voice37_judge.py A_CONTROL.json A_CANDIDATE.json B_CONTROL.json B_CANDIDATE.json
    python docs/experiments/scripts/voice37_judge.py --rule 37c A_CONTROL.json A_CANDIDATE.json B_CONTROL.json B_CANDIDATE.json

A: `bench/voice_levels.py --paths stream` (rows by peak level; 12.0 is 12 dB past full scale); B: `bench/voice_walking.py
--vad silero` (rows by speech-to-noise ratio, and the noise alone).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def levels(path: Path, kind: str = "stream") -> dict[float, dict]:
    return {r["peak_dbfs"]: r for r in json.loads(path.read_text())["rows"] if r["path"] == kind}


def checks_37c(ac: dict[float, dict], ak: dict[float, dict], files: dict[float, dict], brc: dict[str, dict],
               brk: dict[str, dict], nc: dict, nk: dict) -> dict[str, bool]:
    """Round voice37c's conditions (docs/experiments/rules/voice37c_rule.txt)."""
    pts = 100.0
    far, found_more, loud = (-44.0, -38.0), (-44.0, -38.0, -32.0), (-26.0, -14.0, -3.0, 12.0)
    return {
        "(1) no false walk": all(r["false_walks"] == 0 for r in [*ak.values(), *brk.values()]),
        "(2) -44 and -38: commands >= control + 15 points": all(
            ak[p]["command_accuracy"] * pts >= ac[p]["command_accuracy"] * pts + 15 for p in far),
        "(3) -32 ... clipped: commands >= control - 1.0 point each": all(
            ak[p]["command_accuracy"] * pts >= ac[p]["command_accuracy"] * pts - 1.0 for p in (-32.0, *loud)),
        "(4a) -26 ... clipped: other words <= control + 1.0 point each": all(
            ak[p]["oov_accepted"] * pts <= ac[p]["oov_accepted"] * pts + 1.0 for p in loud),
        "(4b) -44, -38, -32: other words <= the file path's + 3.0 points each": all(
            ak[p]["oov_accepted"] * pts <= files[p]["oov_accepted"] * pts + 3.0 for p in found_more),
        "(5a) B: commands >= control - 1.0 point, other words <= control + 1.0 each": all(
            brk[s]["command_accuracy"] * pts >= brc[s]["command_accuracy"] * pts - 1.0
            and brk[s]["oov_accepted"] * pts <= brc[s]["oov_accepted"] * pts + 1.0 for s in brc),
        "(5b) B noise alone: no command, segments <= control + 1": not nk["commands_heard"]
        and nk["segments"] <= nc["segments"] + 1,
        "(6) p50 at -26 and -3 <= control + 5 ms": all(
            ak[p]["end_of_speech_to_segment_ms_p50_p90"][0] <= ac[p]["end_of_speech_to_segment_ms_p50_p90"][0] + 5
            for p in (-26.0, -3.0)),
    }


def main() -> int:
    args = sys.argv[1:]
    rule = "37"
    if args[:1] == ["--rule"]:
        rule, args = args[1], args[2:]
    ac, ak = levels(Path(args[0])), levels(Path(args[1]))
    bc, bk = (json.loads(Path(p).read_text()) for p in args[2:4])
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
    if rule == "37c":
        files = levels(Path(args[0]), "file")
        print("A file path (the engine alone), other words: "
              + ", ".join(f"{p:.0f}: {r['oov_accepted']:.3f}" for p, r in files.items()))
        checks = checks_37c(ac, ak, files, brc, brk, nc, nk)
    else:
        checks = checks_37(ac, ak, brc, brk, nc, nk)
    for name, ok in checks.items():
        print(f"{'holds' if ok else 'FAILS':6} {name}")
    passed = all(checks.values())
    print("passes" if passed else "does NOT pass")
    return 0 if passed else 1


def checks_37(ac: dict[float, dict], ak: dict[float, dict], brc: dict[str, dict], brk: dict[str, dict], nc: dict,
              nk: dict) -> dict[str, bool]:
    """Rounds voice37 and 37b's conditions."""
    pts = 100.0
    trained = [-32.0, -26.0, -14.0, -3.0, 12.0]
    return {
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


if __name__ == "__main__":
    raise SystemExit(main())
