"""Rule voice23's conditions (the same as rule voice22's) on two `bench/voice_bench.py --json` files.

    python docs/experiments/scripts/voice23_judge.py CONTROL.json CANDIDATE.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

NEURAL = ("piper:en_US-joe-medium", "kokoro:jm_kumo", "kokoro:jf_nezumi")
EIGHT = ("flite:rms", "flite:slt", "festival:kal", "festival:slt_hts", "mbrola:us1", "rhvoice:slt", "pico:en-US",
         "pico:en-GB")


def figures(path: Path) -> dict[str, float]:
    rows = {r["family"]: r for r in json.loads(path.read_text()) if "family" in r}

    def pooled(families: tuple[str, ...]) -> tuple[int, int, int, int]:
        heard = sum(round(rows[f]["command_accuracy"] * rows[f]["n"]["commands"]) for f in families)
        cmds = sum(rows[f]["n"]["commands"] for f in families)
        taken = sum(round(rows[f]["oov_accepted"] * rows[f]["n"]["oov"]) for f in families)
        oov = sum(rows[f]["n"]["oov"] for f in families)
        return heard, cmds, taken, oov

    out: dict[str, float] = {}
    for name, fams in (("neural", NEURAL), ("piper", NEURAL[:1]), ("all", ("ALL",)), ("eight", EIGHT)):
        heard, cmds, taken, oov = pooled(fams)
        out[f"{name}_heard"], out[f"{name}_cmds"], out[f"{name}_taken"], out[f"{name}_oov"] = heard, cmds, taken, oov
        out[f"{name}_points"] = 100 * (heard / cmds - taken / oov)
    for f in NEURAL[1:]:
        out[f"{f}_heard"] = round(rows[f]["command_accuracy"] * rows[f]["n"]["commands"])
    out["all_accuracy"], out["all_oov"] = rows["ALL"]["command_accuracy"], rows["ALL"]["oov_accepted"]
    out["go_confirmed"] = rows["ALL"]["of_which_asked_and_confirmed"]
    out["go_heard"] = rows["ALL"]["by_command"].get("go", 0.0)
    out["one_edit"] = 100 * rows["one-edit-heldout"]["oov_accepted"]
    out["walks"] = sum(r["false_walks_direct"] for r in rows.values())
    out["asks"] = sum(r["false_asks"] for f, r in rows.items() if f in ("ALL", "one-edit-heldout") or f in EIGHT[3:]
                      or f in NEURAL)
    out["rtf"] = max(r["rtf"] for r in rows.values())
    return out


def verdict(checks: dict[str, bool]) -> int:
    """Print each condition and whether the candidate passes them all; the exit code (0)."""
    for name, ok in checks.items():
        print(f"{'holds' if ok else 'FAILS':6} {name}")
    print("PASSES" if all(checks.values()) else "does NOT pass")
    return 0


def main() -> int:
    c, k = figures(Path(sys.argv[1])), figures(Path(sys.argv[2]))
    for key in c:
        print(f"{key:28} {c[key]:10.3f} {k[key]:10.3f}")
    checks = {
        "(1) zero direct false walks": k["walks"] == 0,
        "(2) neural points >= control + 5.0": k["neural_points"] >= c["neural_points"] + 5.0,
        "(3) Piper points >= control": k["piper_points"] >= c["piper_points"],
        "(4) ALL points >= control - 1.0": k["all_points"] >= c["all_points"] - 1.0,
        "(5) eight families points >= control - 1.0": k["eight_points"] >= c["eight_points"] - 1.0,
        "(6) one-edit accepted <= control + 1.0": k["one_edit"] <= c["one_edit"] + 1.0,
        "(7) false asks <= control + 10": k["asks"] <= c["asks"] + 10,
        "(8) RTF <= 0.1": k["rtf"] <= 0.1,
    }
    return verdict(checks)


if __name__ == "__main__":
    sys.exit(main())
