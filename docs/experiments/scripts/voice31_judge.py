"""Rule voice31's conditions ("stop" within a phrase) on the control and candidate outputs of its three runs.

    python docs/experiments/scripts/voice31_judge.py BENCH_CONTROL.json BENCH_CANDIDATE.json \
        PHRASES_CONTROL.json PHRASES_CANDIDATE.json RECORDINGS_CONTROL.json RECORDINGS_CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from voice23_judge import figures, verdict  # noqa: E402
from voice27_judge import latency_p50  # noqa: E402
from voice30_judge import noise  # noqa: E402

EXTRA = ("festival:slt_hts", "pico:en-US", "pico:en-GB", "mbrola:us1", "rhvoice:slt", "piper:en_US-joe-medium",
         "kokoro:jm_kumo", "kokoro:jf_nezumi")
STOP_GROUPS = ("stop in a phrase", "stop forbidden")


def extra_taken(path: Path) -> float:
    rows = {r["family"]: r for r in json.loads(path.read_text()) if "family" in r}
    taken = sum(round(rows[f]["oov_accepted"] * rows[f]["n"]["oov"]) for f in EXTRA)
    return 100 * taken / sum(rows[f]["n"]["oov"] for f in EXTRA)


def rtf_max(path: Path) -> float:
    return max(float(r["rtf"]) for r in json.loads(path.read_text()) if "family" in r)


def phrases(path: Path) -> dict[str, object]:
    d = json.loads(path.read_text())
    groups = d["one_utterance"]
    stop = sum(groups[g]["heard"].get("stop", 0) for g in STOP_GROUPS)
    n_stop = sum(groups[g]["clips"] for g in STOP_GROUPS)
    others = sum(n for g, row in groups.items() if g not in STOP_GROUPS for h, n in row["heard"].items() if h != "none")
    moves = {g: (row["heard"].get("go: walk", 0), row["heard"].get("go: ask", 0)) for g, row in groups.items()}
    streams = {k: (row["walked"], row["asked"]) for k, row in d["two_utterances"].items()}
    return {"stop_points": 100 * stop / n_stop, "others": others, "moves": moves, "streams": streams}


def recordings(path: Path) -> int:
    """Commands published on the recordings, streamed and word by word."""
    rows = [r for r in json.loads(path.read_text()) if r["engine"] == "spotter"]
    return sum(sum(r["published"].values()) + r["alone"]["other_words_taken"] + r["alone"]["command_words_heard"]
               for r in rows)


def main() -> int:
    a_c, a_k, b_c, b_k, c_c, c_k = (Path(p) for p in sys.argv[1:7])
    c, k = figures(a_c), figures(a_k)
    for d, path in ((c, a_c), (k, a_k)):
        d["latency_p50"], d["noise"], d["extra_taken"], d["rtf_max"] = (
            latency_p50(path), noise(path), extra_taken(path), rtf_max(path))
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    pc, pk = phrases(b_c), phrases(b_k)
    for key in pc:
        print(f"{key:28} {pc[key]}  ->  {pk[key]}")
    rc, rk = recordings(c_c), recordings(c_k)
    print(f"{'recordings: published':28} {rc} -> {rk}")
    checks = {
        "(1) stop in a phrase + stop forbidden heard as stop >= control + 15 points":
            pk["stop_points"] >= pc["stop_points"] + 15,  # type: ignore[operator]
        "(2) other groups' commands <= control + 2; walks and questions identical":
            pk["others"] <= pc["others"] + 2 and pk["moves"] == pc["moves"] and pk["streams"] == pc["streams"],  # type: ignore[operator]
        "(3) zero direct false walks, false asks <= control": k["walks"] == 0 and k["asks"] <= c["asks"],
        "(4) ALL other words <= control + 0.5 points, accuracy >= control - 0.3 points":
            100 * k["all_oov"] <= 100 * c["all_oov"] + 0.5 and 100 * k["all_accuracy"] >= 100 * c["all_accuracy"] - 0.3,
        "(5) one-edit accepted <= control + 1.0 point": k["one_edit"] <= c["one_edit"] + 1.0,
        "(6) extra rows' other words <= control + 1.0 point": k["extra_taken"] <= c["extra_taken"] + 1.0,
        "(7) noise <= control, RTF <= 0.1, latency p50 <= control + 10 ms":
            k["noise"] <= c["noise"] and k["rtf_max"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 10,
        "(8) no command added on the recordings": rk <= rc,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
