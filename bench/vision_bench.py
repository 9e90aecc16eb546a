"""Vision benchmark on held-out frames: per-class precision and recall, the false-mark rate, recall by
mark size, tilt, blur and finger occlusion, and single-thread frames per second at 640x480.

    .venv/bin/python bench/vision_bench.py [--frames 2000] [--seed 4242] [--split heldout|blind|tuning]
                                           [--failures DIR] [--json] [--set KEY=VALUE ...]
                                           [--hand-variety SHARE] [--hand-drawn SHARE] [--without KIND ...]
                                           [--plus-signs]
                                           [--lens K [--calibrated [--keep-matrix]]] [--flicker DEPTH [--flicker-wave sine|pwm]]
                                           [--glare PEAK]
                                           (--hand-variety, --hand-drawn, --without, --calibrated, --keep-matrix:
                                            tuning split only)

`--split heldout` (the default, and the figure to report) draws frames with
`services/vision/heldout.py`, a generator the detector was never tuned on (other drawing code,
backgrounds, fonts, card proportions, inks, hands, lighting and blur ranges); `--split tuning` uses
`services/vision/synthetic.py`, the generator the detector was tuned on; `--split blind` uses
`services/vision/blind.py`, a third generator written blind (without reading the detector or the other
two generators) after 22 rounds of held-out decisions, to ask whether the held-out figures carry over
(it adds a recall slice by how the mark was made; `--plus-signs`: its mark-free frames show upright plus
signs, which the product's contract makes X marks turned by 45 degrees). With the tuning split,
`--hand-variety`: that share of its cards with fingers get people's variety of fingers,
`Variation.hand_variety`; `--hand-drawn S`: that
share of its marks drawn by hand with a pen, `Variation.hand_drawn`; `--without KIND`: no clutter of that kind
(`Variation.kinds`; the frames then differ from the seed's default ones); `--lens K`: every
frame through a lens with barrel distortion K, `Variation.lens`; `--calibrated`: each such frame undistorted
with the lens's calibration in OpenCV's model, `synthetic.lens_calibration`, by the service's `Undistorter`,
and scored against the same seed's lens-free labels where the undistorted frame shows them; `--keep-matrix`:
undistorted with the calibration's own camera matrix, which cuts the edges. `--flicker DEPTH` (any split): every frame
as a rolling-shutter camera sees it under mains-powered light (`bench/flicker.py`), which no generator draws. `--glare PEAK`
(any split): a lamp's reflection on a glossy or laminated card over every mark (`bench/glare.py`; no generator draws it),
with a recall slice by the share of the mark's box it washes out to white. With `--split heldout`,
`--lens K` shows the held-out scenes through a lens in OpenCV's radial model (k1 = -K, focal length the
frame's width: `heldout.lens_maps`), the labels the ink's distorted extent. Frames cycle X, O,
TRIANGLE and mark-free. A detection is correct when its class equals the frame's mark and its box
overlaps the true box (intersection over the smaller box >= 0.5); anything else counts against the
detected class's precision. With `--split heldout`, and `--split tuning` without a lens, every false mark is also
charged to what it lies on (`lies_on`: the frame's true mark, taken for another shape or boxed twice, else the clutter
or held card under it, else the background; the held-out generator records what it drew, `heldout.Drawn`, the tuning
one the pixels each thing changed, `synthetic.Painted`, `lies_on_painted`): a table of what fools the detector.
Timing covers `MarkDetector.detect` only, with OpenCV on one thread, by the wall clock and by this process's CPU time
(on a shared machine the first includes waiting for a core).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import statistics
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import Annotated, Any

import cv2
import numpy as np
import typer

from bench.flicker import WAVES, flicker_bands
from bench.glare import glare_spot
from schemas.messages import Shape
from services.vision.detector import Box, Detection, MarkDetector, box_overlap, parse_settings
from services.vision.verifier import Verifier

CLASSES: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
TIMED_FRAMES = 200
SIZE_BINS = ((0, 80), (80, 160), (160, 300), (300, 10_000))
TILT_BINS = ((0, 15), (15, 30), (30, 46))
FLICKER_BINS = ((0, 0.1), (0.1, 0.3), (0.3, 1.0))
GLARE_BINS = ((0, 0.01), (0.01, 0.1), (0.1, 0.25), (0.25, 1.01))
BLUR_BINS = ((0, 1.5), (1.5, 8), (8, 14), (14, 21))


def _bin(value: float, bins: tuple[tuple[float, float], ...]) -> str:
    for lo, hi in bins:
        if lo <= value < hi:
            return f"{lo:g}-{hi:g}"
    return "other"


def main(
    frames: Annotated[int, typer.Option(help="frames to generate")] = 2000,
    seed: Annotated[int, typer.Option(help="generator seed")] = 4242,
    split: Annotated[str, typer.Option(help="heldout (report this), blind (a third generator) or tuning")] = "heldout",
    failures: Annotated[Path | None, typer.Option(help="write misses and false marks here")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
    settings: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            help="KEY=VALUE: a DetectorConfig field (loose_contrast=45), or the verifier's thresholds or "
            "loose_thresholds (thresholds=0.25,0.5,0.5): to compare variants on the tuning split",
        ),
    ] = None,
    hand_variety: Annotated[
        float,
        typer.Option(help="tuning split only: share of cards with fingers given people's variety of fingers"),
    ] = 0.0,
    hand_drawn: Annotated[
        float, typer.Option(help="tuning split only: share of marks drawn by hand with a pen (Variation.hand_drawn)")
    ] = 0.0,
    without: Annotated[
        list[str] | None,
        typer.Option(
            help="tuning split only: leave this kind of clutter out (repeatable; synthetic.DISTRACTORS), e.g. "
            "filled_triangle, whose painted walls round vision61's definition makes marks"
        ),
    ] = None,
    plus_signs: Annotated[
        bool,
        typer.Option(help="blind split only: mark-free frames show upright plus signs (an X turned by 45 degrees)"),
    ] = False,
    lens: Annotated[
        float,
        typer.Option(
            help="the lens's barrel distortion k for every frame: the tuning generator's own model "
            "(Variation.lens), or for the held-out split OpenCV's radial model with k1 = -k (heldout.lens_maps)"
        ),
    ] = 0.0,
    calibrated: Annotated[
        bool,
        typer.Option(
            help="with --lens: undistort every frame with the lens's calibration in OpenCV's model "
            "(synthetic.lens_calibration), as --calibration does in the service, before detection"
        ),
    ] = False,
    keep_matrix: Annotated[
        bool,
        typer.Option(help="with --calibrated: undistort with the calibration's own camera matrix (edges cut)"),
    ] = False,
    flicker: Annotated[
        float,
        typer.Option(
            help="any split: every frame under mains-powered light through a rolling shutter, bands of up to this "
            "depth of the light's flicker (0.3: a fluorescent tube; 1: a cheap LED lamp); see bench/flicker.py",
        ),
    ] = 0.0,
    flicker_wave: Annotated[
        str, typer.Option(help="with --flicker: sine (a tube's 100/120 Hz ripple) or pwm (an LED dimmer's square wave)")
    ] = "sine",
    glare: Annotated[
        float,
        typer.Option(
            help="any split: a lamp's reflection on a glossy card over every mark, its peak up to this share of the "
            "sensor's white in linear light (1: its centre just saturates; 2: a wide washed-out patch); see "
            "bench/glare.py",
        ),
    ] = 0.0,
) -> None:
    cv2.setNumThreads(1)
    if hand_variety and split != "tuning":
        raise typer.BadParameter("--hand-variety is a tuning-generator setting (--split tuning)")
    if hand_drawn and split != "tuning":
        raise typer.BadParameter("--hand-drawn is a tuning-generator setting (--split tuning)")
    if without and split != "tuning":
        raise typer.BadParameter("--without is a tuning-generator setting (--split tuning)")
    if plus_signs and split != "blind":
        raise typer.BadParameter("--plus-signs is a blind-generator setting (--split blind)")
    if lens and split == "blind":
        raise typer.BadParameter("--lens is a tuning or held-out generator setting (the blind one has its own optics)")
    if calibrated and (not lens or split != "tuning"):
        raise typer.BadParameter("--calibrated needs --lens K and --split tuning")
    if not 0.0 <= flicker <= 1.0:
        raise typer.BadParameter("--flicker is the light's flicker depth, 0 to 1")
    if flicker_wave not in WAVES:
        raise typer.BadParameter("--flicker-wave is sine or pwm")
    if not 0.0 <= glare <= 10.0:
        raise typer.BadParameter("--glare is the highlight's peak, 0 to 10 times the sensor's white")
    try:
        frame_of = _generator(
            split, seed, hand_variety, lens, calibrated, keep_matrix, hand_drawn, plus_signs, tuple(without or ())
        )
    except ValueError as exc:  # a held-out lens the model cannot show, or clutter the generator does not draw
        raise typer.BadParameter(str(exc), param_hint="--without" if without else "--lens") from None
    det = _detector(settings or [])
    tp: dict[Shape, int] = defaultdict(int)
    fp: dict[Shape, int] = defaultdict(int)
    n_true: dict[Shape, int] = defaultdict(int)
    slices: dict[str, dict[str, list[int]]] = defaultdict(lambda: defaultdict(lambda: [0, 0]))
    empty_frames = empty_with_marks = 0
    times: list[float] = []
    cpu = 0.0  # this process's CPU seconds in detect: unlike wall time, not inflated by other load
    kept: list[np.ndarray] = []
    what = getattr(frame_of, "lies_on", None)  # held-out and tuning frames: what false marks lie on
    false_on: dict[str, Counter[str]] = defaultdict(Counter)
    if failures:
        failures.mkdir(parents=True, exist_ok=True)
    for i in range(frames):
        truth = CLASSES[i % len(CLASSES)]
        img, label, meta = frame_of(truth)
        if flicker:  # its own draws, so the scenes are the seed's own
            img, amplitude = flicker_bands(img, np.random.default_rng((seed, i)), flicker, flicker_wave)
            meta = {**meta, "flicker_amplitude": _bin(amplitude, FLICKER_BINS)} if label is not None else meta
        if glare:  # its own draws too (the scenes stay the seed's own), over the flicker's bands if any
            img, washed = glare_spot(img, np.random.default_rng((seed, i, 1)), glare, label[1] if label else None)
            meta = {**meta, "glare_washed": _bin(washed, GLARE_BINS)} if label is not None else meta
        if len(kept) < TIMED_FRAMES:
            kept.append(img)
        t0, c0 = time.perf_counter(), time.process_time()
        found = det.detect(img)
        times.append(time.perf_counter() - t0)
        cpu += time.process_time() - c0
        hit = wrong = False
        ons: set[str] = set()  # what this frame's false marks lie on (held-out frames)
        for d in found:
            if label is not None and not hit and d.shape == label[0] and box_overlap(d.box, label[1]) >= 0.5:
                hit = True
                tp[d.shape] += 1
            else:
                fp[d.shape] += 1
                wrong = True
                if what is not None:
                    ons.add(on := what(d.box, label[1] if label else None))
                    false_on[on][d.shape.value] += 1
        if label is None:
            empty_frames += 1
            empty_with_marks += bool(found)
            for on in ons:  # every mark there is false
                false_on[on]["mark_free_frames"] += 1
        else:
            n_true[label[0]] += 1
            for name, value in meta.items():
                cell = slices[name][value]
                cell[0] += hit
                cell[1] += 1
        if failures and (wrong or (label is not None and not hit)):
            _save_failure(failures, i, img, label, found)
    per_class = {
        s.value: {
            "frames": n_true[s],
            "precision": round(tp[s] / (tp[s] + fp[s]), 4) if tp[s] + fp[s] else None,
            "recall": round(tp[s] / n_true[s], 4) if n_true[s] else None,
            "false": fp[s],
            "missed": n_true[s] - tp[s],
        }
        for s in Shape
    }
    ms = sorted(t * 1000 for t in times)
    result: dict[str, Any] = {
        "split": split,
        "frames": frames,
        "seed": seed,
        "hand_variety": hand_variety,
        "hand_drawn": hand_drawn,
        **({"without": list(without)} if without else {}),
        **({"plus_signs": plus_signs} if split == "blind" else {}),
        "lens": lens,
        "calibrated": calibrated,
        "keep_matrix": keep_matrix,
        "flicker": flicker,
        **({"flicker_wave": flicker_wave} if flicker else {}),
        "glare": glare,
        "settings": list(settings or []),  # --set as given: what this run changed from the defaults
        "resolution": "640x480",
        "opencv": cv2.__version__,
        "threads": cv2.getNumThreads(),
        "missing_fonts": _missing_fonts(split),
        "per_class": per_class,
        "mark_free_frames": empty_frames,
        "false_mark_rate": round(empty_with_marks / empty_frames, 4) if empty_frames else None,
        **({"false_marks_on": _false_on(false_on)} if what is not None else {}),
        "recall_by": {
            name: {k: {"recall": round(v[0] / v[1], 3), "n": v[1]} for k, v in sorted(cells.items())}
            for name, cells in slices.items()
        },
        "fps_single_thread": round(len(times) / sum(times), 1),
        "fps_per_cpu_second": round(len(times) / cpu, 1) if cpu > 0 else None,
        "load_average": [round(v, 2) for v in os.getloadavg()],
        "fps_single_thread_best_pass": _timed_passes(det, kept),
        "ms_per_frame": {
            "mean": round(statistics.fmean(ms), 2),
            "p50": round(ms[len(ms) // 2], 2),
            "p99": round(ms[int(len(ms) * 0.99) - 1], 2),
            "max": round(ms[-1], 2),
        },
    }
    print(json.dumps(result, indent=2) if as_json else _tables(result))


def _detector(settings: list[str]) -> MarkDetector:
    rest: list[str] = []
    limits: list[tuple[str, str]] = []  # the verifier's own thresholds, set after it is loaded
    for item in settings:
        key, _, value = item.partition("=")
        if key in ("thresholds", "loose_thresholds"):
            limits.append((key, value))
        else:
            rest.append(item)
    try:
        config = parse_settings(rest)  # the service's own parsing (--detector, HRI_VISION_DETECTOR)
    except ValueError as exc:
        raise typer.BadParameter(f"--set: {exc} (or the verifier's thresholds / loose_thresholds)") from None
    verifier = Verifier.load(Path(config.verifier_model)) if config.verifier_model else Verifier.load()
    for key, value in limits:
        verifier = dataclasses.replace(verifier, **{key: tuple(float(v) for v in value.split(","))})  # type: ignore[arg-type]
    return MarkDetector(config, verifier=verifier)


Meta = dict[str, str]
FrameFn = Any  # Callable[[Shape | None], tuple[np.ndarray, tuple[Shape, box] | None, Meta]]


def lies_on(gen: Any, box: Box, truth: Box | None) -> str:
    """What a false mark at `box` in a held-out generator's (`gen`) last frame lies on: the frame's true mark (at
    `truth`: taken for another shape, or a second box over it), else the last thing drawn under the false mark's
    centre (`heldout.Drawn`: its box grown by a tenth, a cable's curve within its half-width and a quarter of the
    false mark's size), else the background (a scikit-image picture's name, or "room")."""
    if truth is not None and box_overlap(box, truth) >= 0.3:
        return "the mark itself"
    cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
    for d in reversed(gen.drawn):
        if d.curve is not None:
            if _to_polyline(d.curve, (cx, cy)) <= d.width / 2 + max(box[2], box[3]) / 4:
                return d.kind
            continue
        x, y, w, h = d.box
        if x - w / 10 <= cx <= x + w * 1.1 and y - h / 10 <= cy <= y + h * 1.1:
            return d.kind
    return f"background: {gen.background}"


def lies_on_painted(gen: Any, box: Box, truth: Box | None) -> str:
    """What a false mark at `box` in a recording tuning generator's (`gen`, `SceneGenerator.record`) last frame lies
    on: the frame's true mark (as `lies_on`), else the last thing drawn - the held card, then the clutter newest
    first (`synthetic.Painted`) - that changed a pixel within a quarter of the false mark's size of its centre, else
    the background (a scikit-image sample's name, or "procedural")."""
    if truth is not None and box_overlap(box, truth) >= 0.3:
        return "the mark itself"
    x, y, w, h = box
    r, cx, cy = max(w, h) / 4, x + w / 2, y + h / 2
    near = (slice(max(0, int(cy - r)), int(cy + r) + 1), slice(max(0, int(cx - r)), int(cx + r) + 1))
    for painted in ([gen.card] if gen.card is not None else []) + gen.painted[::-1]:
        if painted.mask[near].any():
            return str(painted.kind)
    return f"background: {gen.background}"


def _to_polyline(points: np.ndarray, at: tuple[float, float]) -> float:
    """The distance from point `at` to the polyline through `points` ((n, 2), n >= 2)."""
    p0, d = points[:-1], np.diff(points, axis=0)
    c = np.asarray(at, np.float64)
    t = np.clip(((c - p0) * d).sum(axis=1) / np.maximum((d * d).sum(axis=1), 1e-12), 0.0, 1.0)
    return float(np.min(np.hypot(*(p0 + t[:, None] * d - c).T)))


def _generator(split: str, seed: int, hand_variety: float = 0.0, lens: float = 0.0,
               calibrated: bool = False, keep_matrix: bool = False, hand_drawn: float = 0.0,
               plus_signs: bool = False, without: tuple[str, ...] = ()) -> FrameFn:
    if split in ("heldout", "blind"):
        if split == "heldout":
            from services.vision.heldout import HeldOutGenerator

            gen: Any = HeldOutGenerator(seed=seed, lens=lens)
        else:
            from services.vision.blind import BlindGenerator

            gen = BlindGenerator(seed=seed, plus_signs=plus_signs)

        def held(shape: Shape | None) -> tuple[np.ndarray, Any, Meta]:
            img, lab = gen.frame(shape)
            if lab is None:
                return img, None, {}
            meta = {
                "size_px": _bin(lab.size, SIZE_BINS),
                "tilt_deg": _bin(lab.tilt_deg, TILT_BINS),
                "blur_px": _bin(lab.blur_px, BLUR_BINS),
                "finger_near_mark": str(lab.finger_near).lower(),
            }
            if lab.shape is Shape.TRIANGLE:
                meta["triangle"] = "filled" if lab.filled else "outline"
            if split == "blind":  # how the mark was made: a marker, print, tape, a sticker
                meta["style"] = lab.style
            return img, (lab.shape, lab.box), meta

        if split == "heldout":  # it records what it drew: what each false mark lies on
            held.lies_on = functools.partial(lies_on, gen)  # type: ignore[attr-defined]
        return held
    if split == "tuning":
        from services.vision.synthetic import DISTRACTORS, SceneGenerator, Variation

        unknown = sorted(set(without) - set(DISTRACTORS))
        if unknown:
            raise ValueError(f"no such clutter {', '.join(unknown)}: one of {', '.join(DISTRACTORS)}")
        kinds = tuple(k for k in DISTRACTORS if k not in without)
        tgen = SceneGenerator(
            seed=seed,
            variation=Variation(hand_variety=hand_variety, hand_drawn=hand_drawn, lens=lens, kinds=kinds),
        )
        if calibrated:  # the same scenes without the lens (the lens draws nothing): where the marks are
            from services.vision.calibration import Undistorter
            from services.vision.synthetic import lens_calibration

            pinhole = SceneGenerator(
                seed=seed, variation=Variation(hand_variety=hand_variety, hand_drawn=hand_drawn, kinds=kinds)
            )
            undistort = Undistorter(lens_calibration(lens, pinhole.width, pinhole.height),
                                    None if keep_matrix else 1.0)
            new = undistort.new_matrix(pinhole.width, pinhole.height)
            # a pinhole point x shows at new_f (x - centre) / f + new_centre in the undistorted frame
            view = (new[0, 0] / (pinhole.width / 2), new[1, 1] / (pinhole.width / 2), new[0, 2], new[1, 2])

        def tuning(shape: Shape | None) -> tuple[np.ndarray, Any, Meta]:
            scene = tgen.scene(shape)
            img, labels = tgen.render(scene)
            inside: dict[str, str] = {}
            if calibrated:  # the frame undistorted; the marks where the undistorted frame shows them
                _, labels = pinhole.render(pinhole.scene(shape))
                img = undistort(img)
                labels = [_viewed(lab, view, img.shape[1], img.shape[0]) for lab in labels]
                if labels:
                    x, y, w, h = labels[0].box
                    whole = x >= 0 and y >= 0 and x + w <= img.shape[1] and y + h <= img.shape[0]
                    inside = {"whole_in_undistorted_frame": str(whole).lower()}
            if not labels:
                return img, None, {}
            tilt = float(np.hypot(*scene.tilt))
            meta = {
                "size_px": _bin(max(labels[0].box[2:]), SIZE_BINS),
                "tilt_deg": _bin(tilt, TILT_BINS),
                "blur_px": _bin(scene.blur[0], BLUR_BINS),
                # fingers reaching from the card's edge towards the mark (over its edge for some)
                "finger_near_mark": str(scene.fingers > 0).lower(),
                **({"by_hand": str(scene.by_hand is not None).lower()} if hand_drawn else {}),
                **({"triangle": "filled" if scene.filled else "outline"} if labels[0].shape is Shape.TRIANGLE else {}),
                **inside,
            }
            return img, (labels[0].shape, labels[0].box), meta

        if not lens:  # it records what it drew (through a lens it would be elsewhere): what false marks lie on
            tgen.record = True
            tuning.lies_on = functools.partial(lies_on_painted, tgen)  # type: ignore[attr-defined]
        return tuning
    raise typer.BadParameter(f"split must be heldout, blind or tuning, got {split!r}")


def _viewed(label: Any, view: tuple[float, float, float, float], width: int, height: int) -> Any:
    """`label`'s box (pinhole scene) where an undistorted frame shows it: `view` is (x scale, y scale, new
    centre x, new centre y), the scene's centre being the frame's."""
    sx, sy, ncx, ncy = view
    x, y, w, h = label.box
    x0, y0 = (x - width / 2) * sx + ncx, (y - height / 2) * sy + ncy
    return dataclasses.replace(label, box=(round(x0), round(y0), round(w * sx), round(h * sy)))


def _missing_fonts(split: str) -> list[str]:
    """The fonts the held-out or blind generator draws with that this machine lacks."""
    if split == "heldout":
        from services.vision.heldout import missing_fonts
    elif split == "blind":
        from services.vision.blind import missing_fonts
    else:
        return []
    return missing_fonts()


def _tables(r: dict[str, Any]) -> str:
    lines = [
        (
            f"split {r['split']}, {r['frames']} frames, seed {r['seed']}, {r['resolution']}, "
            f"OpenCV {r['opencv']}, {r['threads']} thread"
        ),
        f"detector settings: {' '.join(r['settings']) or 'the defaults'}",
        *([f"every frame under flickering light through a rolling shutter, depth up to {r['flicker']:g} "
           f"({r['flicker_wave']})"]
          if r.get("flicker") else []),
        *([f"a lamp's reflection on a glossy card over every mark, its peak up to {r['glare']:g} of the sensor's white"]
          if r.get("glare") else []),
        *(
            [f"NOT the READMEs' frames for this seed: fonts missing (apt-get install fonts-dejavu-core "
             f"fonts-dejavu-extra): {', '.join(r['missing_fonts'])}"]
            if r["missing_fonts"] else []
        ),
        "",
        "class      frames  precision  recall  false  missed",
    ]
    for name, c in r["per_class"].items():
        p = "-" if c["precision"] is None else f"{c['precision']:.3f}"
        rc = "-" if c["recall"] is None else f"{c['recall']:.3f}"
        lines.append(f"{name:<10} {c['frames']:>6}  {p:>9}  {rc:>6}  {c['false']:>5}  {c['missed']:>6}")
    lines.append(f"mark-free frames with a false mark: {r['false_mark_rate']:.2%} of {r['mark_free_frames']}")
    if r.get("false_marks_on"):
        lines += ["", "false marks by what they lie on  X  O  TRIANGLE  (mark-free frames with one)"]
        for on, c in r["false_marks_on"].items():
            lines.append(f"  {on:<30} {c['X']:>3} {c['O']:>3} {c['TRIANGLE']:>3}  ({c['mark_free_frames']})")
    lines.append("")
    for name, cells in r["recall_by"].items():
        row = ", ".join(f"{k}: {v['recall']:.3f} (n={v['n']})" for k, v in cells.items())
        lines.append(f"recall by {name}: {row}")
    m = r["ms_per_frame"]
    lines += [
        "",
        (
            f"frames/s on one thread: {r['fps_single_thread']} over all frames, "
            f"{r['fps_single_thread_best_pass']} best pass over {TIMED_FRAMES} frames in memory"
        ),
        f"ms per frame: mean {m['mean']}, p50 {m['p50']}, p99 {m['p99']}, max {m['max']}",
        (
            f"frames per CPU-second of this process: {r['fps_per_cpu_second']} (wall-clock figures include "
            f"waiting for a core; load average at the end {r['load_average']})"
        ),
    ]
    return "\n".join(lines)


def _timed_passes(det: MarkDetector, frames: list[np.ndarray], passes: int = 3) -> float:
    """Frames per second of the best of `passes` back-to-back passes over frames held in memory."""
    best = 0.0
    for _ in range(passes):
        t0 = time.perf_counter()
        for img in frames:
            det.detect(img)
        best = max(best, len(frames) / (time.perf_counter() - t0))
    return round(best, 1)


def _false_on(counts: dict[str, Counter[str]]) -> dict[str, dict[str, int]]:
    """False marks by what they lie on (`lies_on`), most first: each shape's count and the mark-free frames with one."""
    keys = [s.value for s in Shape] + ["mark_free_frames"]
    rows = {on: {k: c[k] for k in keys} for on, c in counts.items()}
    return dict(sorted(rows.items(), key=lambda kv: (-sum(kv[1][s.value] for s in Shape), kv[0])))


def _save_failure(folder: Path, i: int, img: np.ndarray, label: Any, found: list[Detection]) -> None:
    out = img.copy()
    if label is not None:
        x, y, w, h = label[1]
        cv2.rectangle(out, (x, y), (x + w, y + h), (0, 255, 0), 1)
    for d in found:
        x, y, w, h = d.box
        cv2.rectangle(out, (x, y), (x + w, y + h), (0, 0, 255), 2)
        cv2.putText(out, d.shape.value, (x, max(12, y - 3)), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 255), 1)
    truth = label[0].value if label is not None else "none"
    cv2.imwrite(str(folder / f"{i:05d}_{truth}.jpg"), out)


if __name__ == "__main__":
    typer.run(main)
