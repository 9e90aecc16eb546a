"""Round vision43's reported figure: the committed proposer and a retrained one on the same held-back tuning chunks
of a `proposer_training --cache` file (the last tenth, as the training's own report), all of them and the cluttered
(odd-seed) ones alone, at peaks 0.3 and 0.5: marks found (the right shape, centred in the mark's box) and stray
proposals a frame (`proposer_training.report`).

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision43_heldback.py CACHE.npz MODEL.onnx
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from services.vision.proposer import Proposer
from services.vision.proposer_training import report
from services.vision.training import split_chunks


def main(cache: Path, model: Path) -> None:
    with np.load(cache) as z:
        seeds = z["seeds"].tolist()
        parts = [(z[f"x_{k}"], z[f"y_{k}"]) for k in range(len(seeds))]
    _, val = split_chunks(parts, 0)
    val_seeds = seeds[len(seeds) - len(val) :]
    cluttered = [p for p, s in zip(val, val_seeds, strict=True) if s % 2]
    out: dict[str, object] = {"held_back_seeds": val_seeds}
    for name, proposer in (("committed", Proposer.load()), ("retrained", Proposer.load(model))):
        for t in (0.3, 0.5):
            out[f"{name}_all_at_{t:g}"] = report(proposer, val, t)
            out[f"{name}_cluttered_at_{t:g}"] = report(proposer, cluttered, t)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
