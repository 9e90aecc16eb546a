"""Rule voice35's conditions ("down" within a phrase) on the control and candidate outputs of its three runs.

    python docs/experiments/scripts/voice35_judge.py BENCH_CONTROL.json BENCH_CANDIDATE.json \
        PHRASES_CONTROL.json PHRASES_CANDIDATE.json RECORDINGS_CONTROL.json RECORDINGS_CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import verdict  # noqa: E402
from voice31_judge import recordings  # noqa: E402
from voice34_judge import bench_figures  # noqa: E402

DOWN_PHRASES = ("sit down", "get down", "down there")


def phrases(path: Path) -> dict[str, object]:
    d = json.loads(path.read_text())
    per_phrase = {p: n for row in d["one_utterance"].values() for p, n in row["per_phrase"].items()}
    down = sum(per_phrase[p].get("down", 0) for p in DOWN_PHRASES)
    false_down = sum(n.get("down", 0) for p, n in per_phrase.items() if p not in DOWN_PHRASES)
    rest = {p: {h: k for h, k in n.items() if h not in ("down", "none")} for p, n in per_phrase.items()}
    streams = {f"{part}: {key}": (row["walked"], row["asked"], row["reasoner"])
               for part in ("two_utterances", "meant_pairs") for key, row in d[part].items()}
    sentences = sum(row["any_command"] for row in d["sentences_streamed"].values())
    return {"down": down, "false_down": false_down, "rest": rest, "streams": streams, "sentences": sentences}


def main() -> int:
    a_c, a_k, b_c, b_k, c_c, c_k = (Path(p) for p in sys.argv[1:7])
    c, k = bench_figures(a_c, a_k)
    pc, pk = phrases(b_c), phrases(b_k)
    for key in ("down", "false_down", "sentences"):
        print(f"{key:28} {pc[key]} -> {pk[key]}")
    print(f"{'other labels identical':28} {pc['rest'] == pk['rest']}; streams identical {pc['streams'] == pk['streams']}")
    rc, rk = recordings(c_c), recordings(c_k)
    print(f"{'recordings: published':28} {rc} -> {rk}")
    checks = {
        "(1) down phrases heard as down >= control + 4": pk["down"] >= pc["down"] + 4,  # type: ignore[operator]
        "(2) other phrases: down <= control + 2; other labels identical":
            pk["false_down"] <= pc["false_down"] + 2 and pk["rest"] == pc["rest"],  # type: ignore[operator]
        "(3) streams identical; sentences with a command <= control + 2":
            pk["streams"] == pc["streams"] and pk["sentences"] <= pc["sentences"] + 2,  # type: ignore[operator]
        "(4) zero direct false walks, false asks (ALL) <= control": k["walks"] == 0 and k["all_asks"] <= c["all_asks"],
        "(5) ALL other words <= control + 0.5 points, accuracy >= control - 0.3 points":
            100 * k["all_oov"] <= 100 * c["all_oov"] + 0.5 and 100 * k["all_accuracy"] >= 100 * c["all_accuracy"] - 0.3,
        "(6) one-edit, extra rows <= control + 1.0 point; noise; RTF <= 0.1; latency p50 <= control + 10 ms":
            k["one_edit"] <= c["one_edit"] + 1.0 and k["extra_taken"] <= c["extra_taken"] + 1.0
            and k["noise"] <= c["noise"] and k["rtf_max"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 10,
        "(7) no command added on the recordings": rk <= rc,
    }
    return verdict(checks)


if __name__ == "__main__":
    raise SystemExit(main())
