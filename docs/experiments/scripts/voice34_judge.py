"""Rule voice34's conditions (the warped second look) on the control and candidate outputs of its three runs.

    python docs/experiments/scripts/voice34_judge.py BENCH_CONTROL.json BENCH_CANDIDATE.json \
        PHRASES_CONTROL.json PHRASES_CANDIDATE.json RECORDINGS_CONTROL.json RECORDINGS_CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import voice23_judge  # noqa: E402
import voice31_judge  # noqa: E402
from voice23_judge import figures, verdict  # noqa: E402
from voice27_judge import latency_p50  # noqa: E402
from voice30_judge import noise  # noqa: E402
from voice31_judge import extra_taken, recordings, rtf_max  # noqa: E402

QUIET_GROUPS = ("go forbidden", "go-words", "sentences without stop")
"""Groups whose clips hold no command the robot should act on."""


def bench_figures(control: Path, candidate: Path) -> tuple[dict[str, float], dict[str, float]]:
    """Both `voice_bench.py --json` files' figures (voice23_judge's and the rules' others), printed side by side; a
    family this machine could not speak (no row in either) is left out of the pooled rows."""
    present = {r["family"] for p in (control, candidate) for r in json.loads(p.read_text()) if "family" in r}
    for module, name in ((voice23_judge, "EIGHT"), (voice31_judge, "EXTRA")):
        setattr(module, name, tuple(f for f in getattr(module, name) if f in present))
    c, k = figures(control), figures(candidate)
    for d, path in ((c, control), (k, candidate)):
        d["latency_p50"], d["noise"], d["extra_taken"], d["rtf_max"] = (
            latency_p50(path), noise(path), extra_taken(path), rtf_max(path))
        d["all_asks"] = next(r["false_asks"] for r in json.loads(path.read_text()) if r.get("family") == "ALL")
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    return c, k


def phrases(path: Path) -> dict[str, object]:
    d = json.loads(path.read_text())
    groups = d["one_utterance"]
    walks = {g: row["heard"].get("go: walk", 0) for g, row in groups.items()}
    for part in ("two_utterances", "meant_pairs"):
        for key, row in d[part].items():
            walks[f"{part}: {key}"] = (row["walked"], row["reasoner"]["walked"])
    quiet = sum(n for g in QUIET_GROUPS for h, n in groups[g]["heard"].items() if h != "none")
    asked = sum(row["asked"] + row["reasoner"]["asked"] for row in d["two_utterances"].values())
    return {"walks": walks, "quiet_commands": quiet, "stream_questions": asked,
            "sentences_streamed": d["sentences_streamed"]}


def main() -> int:
    a_c, a_k, b_c, b_k, c_c, c_k = (Path(p) for p in sys.argv[1:7])
    c, k = bench_figures(a_c, a_k)
    pc, pk = phrases(b_c), phrases(b_k)
    for key in pc:
        print(f"{key:28} {pc[key]}  ->  {pk[key]}")
    print(f"{'walks identical':28} {pk['walks'] == pc['walks']}")
    rc, rk = recordings(c_c), recordings(c_k)
    print(f"{'recordings: published':28} {rc} -> {rk}")
    checks = {
        "(1) ALL accuracy >= control + 1.0 point": 100 * k["all_accuracy"] >= 100 * c["all_accuracy"] + 1.0,
        "(2) ALL other words <= control + 0.5 points": 100 * k["all_oov"] <= 100 * c["all_oov"] + 0.5,
        "(3) zero direct false walks, false asks (ALL) <= control + 3": k["walks"] == 0 and k["all_asks"] <= c["all_asks"] + 3,
        "(4) one-edit accepted <= control + 1.0 point": k["one_edit"] <= c["one_edit"] + 1.0,
        "(5) extra rows' other words <= control + 1.0 point": k["extra_taken"] <= c["extra_taken"] + 1.0,
        "(6) noise <= control, RTF <= 0.1, latency p50 <= control + 10 ms":
            k["noise"] <= c["noise"] and k["rtf_max"] <= 0.1 and k["latency_p50"] <= c["latency_p50"] + 10,
        "(7) walks identical; quiet groups' commands <= control + 2; stream questions <= control + 10":
            pk["walks"] == pc["walks"] and pk["quiet_commands"] <= pc["quiet_commands"] + 2  # type: ignore[operator]
            and pk["stream_questions"] <= pc["stream_questions"] + 10,  # type: ignore[operator]
        "(8) no command added on the recordings": rk <= rc,
    }
    return verdict(checks)


if __name__ == "__main__":
    raise SystemExit(main())
