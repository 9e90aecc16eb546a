"""Train the mark verifier (`verifier.npz`) on candidates from the TUNING generator only.

    pip install -e '.[train]'
    python -m services.vision.training [--frames 8000] [--seed 20261123] [--jobs 2]

Frames come from `synthetic.SceneGenerator` (never from `heldout.py`), cycling X, O, TRIANGLE and
mark-free, half of them with the default variation and half with extra clutter (8-14 distractors: more
words, signs and textures to learn 'not a mark' from). Every component that passes the detector's
shape tests is a candidate (`MarkDetector.candidates`, verifier off), and so is every loose one (no
shape found, but ink on a light plain surround: `MarkDetector._loose`), with no claimed shape; its
label is the true mark's class when its box overlaps the true box with IoU >= 0.4, else 'none'. The model is scikit-learn's
`MLPClassifier` (one hidden layer of 64 ReLU units, fixed `random_state`), exported to numpy arrays
(float16 weights); inference needs only numpy and OpenCV. The last tenth of the frames is kept out
of training to report the verifier's effect on the candidates the detector keeps.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from schemas.messages import Shape
from services.vision.detector import DetectorConfig, MarkDetector
from services.vision.synthetic import DISTRACTORS, SceneGenerator, Variation
from services.vision.verifier import CLASSES, MODEL_PATH, Verifier

ORDER: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
# training leans on the hard cases (the tuning generator's defaults in brackets): filled triangles are
# 40 % of triangle marks (25 %; on a card they are marks, on a wall clutter, and only the context
# tells them apart); 60 % of cards have fingers (40 %), half of them over the mark's edge (30 %)
DEFAULT = Variation(filled_triangle=0.4, fingers=0.6, finger_over=0.5)
# the cluttered chunks draw the tuning generator's main sources of false marks three times as often:
# filled triangles off cards (half on plain light walls), text (letters O and X in words) and decoy cards
HARD = ("filled_triangle", "text", "card")
CLUTTERED = DEFAULT.only(distractors=(8, 14), kinds=DISTRACTORS + HARD + HARD)
IOU = 0.4
HIDDEN = 64


def iou(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> float:
    ix = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = a[2] * a[3] + b[2] * b[3] - inter
    return inter / union if union > 0 else 0.0


def harvest(seed: int, frames: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(features, class index into CLASSES, kept by the detector) for every candidate in `frames`
    tuning frames drawn with `seed` (even seeds: default variation; odd: cluttered)."""
    import cv2

    cv2.setNumThreads(1)
    gen = SceneGenerator(seed=seed, variation=CLUTTERED if seed % 2 else DEFAULT)
    det = MarkDetector(DetectorConfig(verify=False))
    feats: list[np.ndarray] = []
    labels: list[int] = []
    kept: list[bool] = []
    for i in range(frames):
        img, truth = gen.frame(ORDER[i % len(ORDER)])
        for c in det.candidates(img):
            label: Shape | None = None
            for t in truth:
                if iou(c.box, t.box) >= IOU:
                    label = t.shape
            feats.append(c.features)
            labels.append(CLASSES.index(label))
            kept.append(c.kept)
    n = len(feats)
    return (
        np.array(feats, np.float32).reshape(n, -1),
        np.array(labels, np.int64),
        np.array(kept, bool),
    )


def main(
    frames: Annotated[int, typer.Option(help="tuning frames to harvest")] = 8000,
    seed: Annotated[int, typer.Option(help="base seed (generator chunks and the MLP)")] = 20261123,
    jobs: Annotated[int, typer.Option(help="harvesting processes")] = 2,
    out: Annotated[Path, typer.Option(help="where to write the model")] = MODEL_PATH,
    threshold_x: Annotated[float, typer.Option(help="probability a claimed X needs")] = 0.25,
    threshold_o: Annotated[float, typer.Option(help="probability a claimed O needs")] = 0.5,
    threshold_triangle: Annotated[float, typer.Option(help="probability a claimed TRIANGLE needs")] = 0.5,
    loose_x: Annotated[float, typer.Option(help="probability a loose candidate needs to be named X")] = 0.6,
    loose_o: Annotated[float, typer.Option(help="... to be named O")] = 0.9,
    loose_triangle: Annotated[float, typer.Option(help="... to be named TRIANGLE")] = 0.85,
) -> None:
    from sklearn.neural_network import MLPClassifier

    chunk = 250
    seeds = [seed + k for k in range((frames + chunk - 1) // chunk)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        parts = list(pool.map(harvest, seeds, [chunk] * len(seeds)))
    n_val = max(1, len(parts) // 10)
    train, val = parts[:-n_val], parts[-n_val:]
    x = np.concatenate([p[0] for p in train])
    y = np.concatenate([p[1] for p in train])
    mean = x.mean(axis=0)
    scale = x.std(axis=0) + 1e-3
    mlp = MLPClassifier(
        hidden_layer_sizes=(HIDDEN,),
        alpha=1e-3,
        batch_size=256,
        max_iter=60,
        early_stopping=True,
        random_state=seed,
    )
    mlp.fit((x - mean) / scale, y)
    missing = sorted(set(range(len(CLASSES))) - {int(c) for c in mlp.classes_})
    if missing:
        raise SystemExit(f"no training candidates of class {missing}: harvest more frames")
    verifier = Verifier(
        mean=mean,
        scale=scale,
        weights=tuple(np.asarray(w) for w in mlp.coefs_),
        biases=tuple(np.asarray(b) for b in mlp.intercepts_),
        thresholds=(threshold_x, threshold_o, threshold_triangle),
        loose_thresholds=(loose_x, loose_o, loose_triangle),
    )
    verifier.save(out)
    verifier = Verifier.load(out)  # report with the stored (float16) weights
    report = {"train_candidates": len(y), "train_by_class": np.bincount(y, minlength=4).tolist()}
    xv = np.concatenate([p[0] for p in val])
    yv = np.concatenate([p[1] for p in val])
    kv = np.concatenate([p[2] for p in val])
    prob = verifier.probabilities(xv)
    claimed = np.argmax(xv[:, -4:], axis=1)  # the one-hot of the claimed shape; 3: a loose candidate
    loose = claimed == 3
    claimed[loose] = np.argmax(prob[loose, :3], axis=1)  # the verifier names a loose one's shape
    need = np.where(
        loose, np.array(verifier.loose_thresholds)[claimed], np.array(verifier.thresholds)[claimed]
    )
    accept = prob[np.arange(len(yv)), claimed] >= need
    true_pos = kv & (yv == claimed)
    false_pos = kv & (yv != claimed)
    loose_true = loose & (yv < 3)
    report.update(
        loose_candidates=int(loose.sum()),
        loose_true_marks=int(loose_true.sum()),
        loose_true_named_right=int((loose_true & (yv == claimed) & accept).sum()),
        loose_false_named=int((loose & (yv != claimed) & accept).sum()),
    )
    report.update(
        held_back_candidates=len(yv),
        argmax_accuracy=round(float(np.mean(np.argmax(prob, axis=1) == yv)), 4),
        detector_true_kept=int(true_pos.sum()),
        detector_true_kept_after_verifier=int((true_pos & accept).sum()),
        detector_false_kept=int(false_pos.sum()),
        detector_false_kept_after_verifier=int((false_pos & accept).sum()),
        model_bytes=out.stat().st_size,
    )
    typer.echo(json.dumps(report, indent=2))


if __name__ == "__main__":
    typer.run(main)
