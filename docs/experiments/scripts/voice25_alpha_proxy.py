"""Tuning data only: the default head's recipe (Whisper tiny.en, the six more recorded speakers in training) with
several L2 penalties, each judged by leaving one recorded training speaker out (bench/voice_proxy.py's plain proxy:
knots on one half of the tune rows without the speaker, figures on its recorded-tune clips of the other half).
No word folds (they move knots, not the fit). Members on ONE BLAS thread (so the runs are comparable with each
other, not with the committed head's members).

    nice -n 15 .venv/bin/python docs/experiments/scripts/voice25_alpha_proxy.py OUT.json 0.1 0.3 1.0
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(ROOT), str(ROOT / "bench")]

import voice_proxy as vp  # noqa: E402

from services.voice.training import train  # noqa: E402

if __name__ == "__main__":
    out, alphas = Path(sys.argv[1]), [float(a) for a in sys.argv[2:]]
    base = replace(train.shipped_recipe(), blas_threads=1, word_folds=0)
    rows = vp.load(train.training_splits(base.sizes), base)
    tune = vp.load(train.TUNE_SPLITS, base)
    result: dict[str, dict] = {}
    for alpha in alphas:
        cfg = replace(base, alpha=alpha)
        per = {}
        for name, d in vp.SPEAKERS.items():
            head, info = vp.fitted_head(rows, d, [12, 13, 14], cfg, out.parent / f"proxy-a{alpha}")
            per[name] = {**vp.plain(head, tune, d, cfg), **info}
            print(json.dumps({"alpha": alpha, "speaker": name, **per[name]["left_out"],
                              "tune": per[name]["tune"]["command_accuracy"]}), flush=True)
        result[str(alpha)] = {"speakers": per, "left_out": vp.mean_row(per, "left_out"), "tune": vp.mean_row(per, "tune")}
        print(json.dumps({"alpha": alpha, "mean_left_out": result[str(alpha)]["left_out"],
                          "mean_tune": result[str(alpha)]["tune"]}), flush=True)
        out.write_text(json.dumps(result, indent=2, default=str))
