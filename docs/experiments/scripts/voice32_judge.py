"""Round voice32's judge (docs/experiments/rules/voice32_rule.txt): control and candidate `voice_phrases.py --json`
outputs of the same seed, run by run -> each condition, and the rows that differ.

    python docs/experiments/scripts/voice32_judge.py A_ctl.json A_cand.json B_ctl.json B_cand.json C_ctl.json C_cand.json
"""

from __future__ import annotations

import json
import sys


def judge(control: dict, candidate: dict, name: str) -> bool:
    ok = True
    strip = lambda d: {k: v for k, v in d.items() if k not in ("knowledge",)}  # noqa: E731
    same = strip(control)["one_utterance"] == strip(candidate)["one_utterance"]
    for part in ("two_utterances", "meant_pairs"):
        for key, row in control[part].items():
            other = candidate[part][key]
            same &= {k: v for k, v in row.items() if k != "reasoner"} == {k: v for k, v in other.items() if k != "reasoner"}
    print(f"{name}: (1) everything but the reasoner identical: {same}")
    ok &= same
    walks_ok = True
    for key, row in control["two_utterances"].items():
        c, d = row["reasoner"], candidate["two_utterances"][key]["reasoner"]
        walks_ok &= d["walked"] <= c["walked"]
        if c != d:
            print(f"    forbidding, {key}: control {c} -> candidate {d}")
    print(f"{name}: (2) forbidding pairs, the reasoner's walks never more: {walks_ok}; walks "
          f"{sum(r['reasoner']['walked'] for r in control['two_utterances'].values())} -> "
          f"{sum(r['reasoner']['walked'] for r in candidate['two_utterances'].values())}, questions "
          f"{sum(r['reasoner']['asked'] for r in control['two_utterances'].values())} -> "
          f"{sum(r['reasoner']['asked'] for r in candidate['two_utterances'].values())}")
    ok &= walks_ok
    meant_ok, turned = True, 0
    for key, row in control["meant_pairs"].items():
        c, d = row["reasoner"], candidate["meant_pairs"][key]["reasoner"]
        meant_ok &= c["walked"] + c["asked"] == d["walked"] + d["asked"]
        turned += c["walked"] - d["walked"]
        if c != d:
            print(f"    meant, {key}: control {c} -> candidate {d}")
    print(f"{name}: (3) meant pairs, walks + questions equal: {meant_ok}; walks that became questions: {turned}")
    return ok and meant_ok


def main() -> int:
    paths = sys.argv[1:]
    ok = True
    for i in range(0, len(paths), 2):
        control, candidate = (json.load(open(p)) for p in paths[i : i + 2])
        ok &= judge(control, candidate, f"{paths[i]} vs {paths[i + 1]}")
    print("(1)-(3) hold" if ok else "a condition fails")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
