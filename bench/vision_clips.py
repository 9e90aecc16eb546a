"""Vision on held-out clips: is a card held up to a walking robot seen, and how soon, once the service's frame
confirmation has had its say (prints figures; not a test).

`bench/vision_bench.py` scores single frames. The robot acts on a stream: an X or triangle acts on its first
frame (1 of 3), an O only once seen in 3 of 4 frames (`services/vision/debounce.py`, the vision service's
`Confirmation`). Frames of one scene are not independent draws: a mark the detector cannot read in one frame is
often unreadable in the next. Here each clip is one held-out scene (`HeldOutGenerator.clip`: the held-out
generator's backgrounds, clutter, cards, hands, light and sensor) seen for 1.2 s at 30 fps by a camera that, in
three clips of four, sways, rolls, bobs and is jolted as a walking robot's head is; the card is held up at frame 6
and stays. Every frame goes through the service's detector and a fresh `Debouncer` with the service's defaults.

Printed per class:
- **seen**: clips in which the class was confirmed while the card was up (what the robot acts on), within 1 s of
  the card going up and at all; the frames from the card going up to its confirmation (p50 / p90 / max) and
  that in milliseconds at 30 fps (detection time not included);
- **frame recall**: the share of the same clips' frames in which the detector found the mark (as
  `vision_bench.py` counts a frame), to set against how often the stream confirms it;
- for mark-free clips, **false events**: clips in which an X or triangle (a needless stop) or an O (a danger
  lifted by nothing: the dangerous one) was confirmed, and the false marks' frame rate;
- **never found**: clips in which the detector found the mark in no frame at all;
- wrong-class events: an O confirmed in a danger clip, an X or triangle in an O clip; **lifted**: a danger clip
  in which, after the danger was confirmed, a frame confirmed an O and no X or triangle (the reasoner, for which
  danger wins only within one observation, would have taken the danger as lifted); **left in danger**: the
  reasoner's latch replayed on the confirmed marks is latched at the clip's end (for an O clip: a false X or
  triangle the O did not lift again);
- the same detections replayed under other windows and under each rule for what may lift a danger (`SAFE_RULES`:
  before round vision31, round vision31's window clear of danger, round vision32's O shown anew, round vision33's
  stale O held while a danger mark is detected);
- seen by camera (walking / standing), by mark size, by the clip's longest motion streak, by a finger near the
  mark, and for triangles by filled or outline.

What a person and a real camera add, each off by default (`HeldOutGenerator.clip`; the same seed gives the same
scenes, cameras and noise with them and without, so a run with them pairs with one without):
- `--hand`: a hand raises the card into view from below (a minimum-jerk reach at a peak of 0.5-2 m/s, 0.2-0.8 s,
  the card turned and straightened on the way, blurred by its own travel), then holds it with drift, tremor and
  wobble; the clock of "seen within 1 s" starts when the hand starts;
- `--rolling-shutter`: rows read out top to bottom over 10-30 ms;
- `--auto-exposure`: the gain follows the frame's brightness (time constant 0.15-0.6 s), so a bright card brought
  up darkens the frames after it;
- `--flicker DEPTH [--flicker-wave sine|pwm]`: the room is lit by a flickering lamp (`bench/flicker.py`, one lamp per
  clip): bright and dark bands across every frame, moving on from frame to frame as the lamp's phase does;
- `--glare PEAK`: the card is glossy (laminated) and a lamp's reflection lies on it (`bench/glare.py`, one highlight
  per clip, up to PEAK of the sensor's white in linear light): drawn over the mark when the card comes into view, it
  follows the card and slides across it at up to one mark's size a second.

    .venv/bin/python bench/vision_clips.py [--clips 100] [--seed 2718] [--hand] [--rolling-shutter] [--auto-exposure]
                                           [--flicker DEPTH [--flicker-wave sine|pwm]] [--glare PEAK] [--json]
                                           [--set KEY=VALUE ...]

`--set` changes a detector setting from `DetectorConfig`'s default, as the service's `--detector` does (to compare a
variant on the very same clips).
"""

from __future__ import annotations

import dataclasses
import json
import statistics
import sys
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import cv2
import numpy as np
import typer

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.flicker import WAVES, draw_lamp, lit  # noqa: E402
from bench.glare import glare_clip  # noqa: E402
from schemas.messages import Shape  # noqa: E402
from services.vision.debounce import DANGER_SHAPES, Confirmation, DebounceConfig, Debouncer  # noqa: E402
from services.vision.detector import Detection, MarkDetector, box_overlap, parse_settings  # noqa: E402
from services.vision.heldout import CLIP_FPS, CLIP_FRAMES, CLIP_SHOWN, HeldOutClip, HeldOutGenerator  # noqa: E402

CLASSES: tuple[Shape | None, ...] = (Shape.X, Shape.O, Shape.TRIANGLE, None)
WITHIN_S = 1.0
SIZE_BINS = ((0, 80), (80, 160), (160, 10_000))
STREAK_BINS = ((0, 1.5), (1.5, 5), (5, 10_000))
SAFE_WINDOWS = ("2/3", "3/4", "3/5", "4/5", "5/6", "6/8")
DANGER_WINDOWS = ("1/1", "1/3", "2/3", "2/4")
SAFE_RULES: dict[str, tuple[str, Confirmation]] = {  # what may lift a danger, replayed on the same detections
    "o_beside_danger": (  # before round vision31
        "an O may be confirmed beside a danger mark",
        Confirmation(clear_of_danger=False, new_safe_only=False),
    ),
    "clear_of_danger": (  # round vision31
        "an O only in a window clear of danger",
        Confirmation(clear_of_danger=True, new_safe_only=False),
    ),
    "new_safe_only": (  # round vision32
        "and not an O that was confirmed before the danger came",
        Confirmation(clear_of_danger=True, new_safe_only=True, stale_held_by_danger=False),
    ),
    "stale_held_by_danger": (  # round vision33
        "and that O is not forgotten in frames with a danger mark",
        Confirmation(clear_of_danger=True, new_safe_only=True, stale_held_by_danger=True),
    ),
}
SERVICE = " (the service's)"


@dataclass
class ClipScore:
    """One clip through the detector and the confirmation."""

    shape: Shape | None
    frames: int = 0
    confirmed_at: int | None = None
    """Frames from the card going up to the first frame its class was confirmed; None: never while it was up."""
    frames_with_mark: int = 0
    frames_found: int = 0
    false_frames: int = 0
    """Frames with a detection that is not the mark (another class, or elsewhere)."""
    confirmed: set[Shape] = field(default_factory=set)
    """Every class confirmed in the clip, the lead-in frames included."""
    lifted: bool = False
    """A danger clip: after its X or triangle was confirmed, a frame confirmed an O and no danger mark (the
    reasoner, for which danger wins within one observation, would have taken the danger as lifted)."""
    left_in_danger: bool = False
    """The reasoner's latch replayed on the confirmed marks (a confirmed X or triangle latches danger, a frame with
    a confirmed O and neither lifts it) is latched at the clip's last frame: the robot would still be stopped."""


def score_clip(
    clip: HeldOutClip, found: list[list[Detection]], confirmed: list[list[Detection]]
) -> ClipScore:
    """A clip's frames' detections and the confirmation's output, frame by frame -> its score."""
    shape = clip.label.shape if clip.label is not None else None
    score = ClipScore(shape, frames=len(found))
    for i, (box, dets, conf) in enumerate(zip(clip.boxes, found, confirmed, strict=True)):
        score.confirmed.update(d.shape for d in conf)
        shapes = {d.shape for d in conf}
        if shapes & DANGER_SHAPES:
            score.left_in_danger = True
        elif Shape.O in shapes:
            score.left_in_danger = False
        if shape in DANGER_SHAPES and score.confirmed_at is not None and Shape.O in shapes:
            score.lifted |= not shapes & DANGER_SHAPES
        if (
            shape is not None
            and i >= clip.shown
            and score.confirmed_at is None
            and any(d.shape == shape for d in conf)
        ):
            score.confirmed_at = i - clip.shown
        hit = wrong = False
        for d in dets:  # as vision_bench.py counts a frame: one detection may be the mark, the rest are false
            if box is not None and not hit and d.shape == shape and box_overlap(d.box, box) >= 0.5:
                hit = True
            else:
                wrong = True
        score.false_frames += wrong
        if box is not None:
            score.frames_with_mark += 1
            score.frames_found += hit
    return score


def detect_clip(detector: MarkDetector, clip: HeldOutClip) -> tuple[list[list[Detection]], float]:
    """The clip's frames through the detector -> each frame's detections, and the CPU seconds spent."""
    found: list[list[Detection]] = []
    cpu = 0.0
    for frame in clip.frames:
        c0 = time.process_time()
        found.append(detector.detect(frame))
        cpu += time.process_time() - c0
    return found, cpu


def confirm(found: list[list[Detection]], confirmation: Confirmation) -> list[list[Detection]]:
    """Each frame's detections through a fresh confirmation, as the service's `Debouncer` does."""
    debounce = Debouncer(confirmation)
    return [debounce.update(dets) for dets in found]


def windows(runs: list[tuple[HeldOutClip, list[list[Detection]]]]) -> dict[str, Any]:
    """The same detections under other confirmation windows: what each costs and buys (the service's are
    `Confirmation()`'s), and under each rule of `SAFE_RULES` for what may lift a danger."""
    out: dict[str, Any] = {"safe": {}, "danger": {}}
    for kind, options in (("safe", SAFE_WINDOWS), ("danger", DANGER_WINDOWS)):
        for window in options:
            confirmation = Confirmation(**{kind: DebounceConfig.parse(window)})
            r = summarise([(score_clip(c, f, confirm(f, confirmation)), c) for c, f in runs])
            shapes = ("O",) if kind == "safe" else ("X", "TRIANGLE")
            lat = [r[n]["ms_to_confirm_p50"] for n in shapes if n in r]
            out[kind][window] = {
                "seen_within_1s": sum(r[n]["seen_within_1s"] for n in shapes if n in r),
                "clips": sum(r[n]["clips"] for n in shapes if n in r),
                "ms_to_confirm_p50": lat,
                "false_events": r.get("none", {}).get(
                    "false_o_events" if kind == "safe" else "false_danger_events"
                ),
                "wrong_class_events": sum(
                    r[n]["wrong_class_events"]
                    for n in ("X", "TRIANGLE", "O")
                    if n in r and (n == "O") == (kind == "danger")
                ),
            }
    for name, (_, confirmation) in SAFE_RULES.items():
        r = summarise([(score_clip(c, f, confirm(f, confirmation)), c) for c, f in runs])
        danger = [r[n] for n in ("X", "TRIANGLE") if n in r]
        out[name] = {
            "service": confirmation == Confirmation(),
            "danger_lifted_events": sum(d["danger_lifted_events"] for d in danger),
            "danger_seen_within_1s": sum(d["seen_within_1s"] for d in danger),
            "o_seen_within_1s": r["O"]["seen_within_1s"] if "O" in r else None,
            "o_ms_to_confirm_p50": r["O"]["ms_to_confirm_p50"] if "O" in r else None,
            "o_left_in_danger": r["O"]["left_in_danger"] if "O" in r else None,
            "false_o_events": r.get("none", {}).get("false_o_events"),
        }
    return out


def _bin(value: float, bins: tuple[tuple[float, float], ...]) -> str:
    return next(f"{lo:g}-{hi:g}" for lo, hi in bins if lo <= value < hi)


def _pct(values: list[int], q: float) -> int | None:
    return sorted(values)[min(len(values) - 1, int(q * len(values)))] if values else None


def summarise(rows: list[tuple[ClipScore, HeldOutClip]]) -> dict[str, Any]:
    within = round(WITHIN_S * CLIP_FPS)
    out: dict[str, Any] = {}
    for shape in CLASSES:
        mine = [(s, c) for s, c in rows if s.shape == shape]
        if not mine:
            continue
        if shape is None:
            out["none"] = {
                "clips": len(mine),
                "false_danger_events": sum(bool(s.confirmed & DANGER_SHAPES) for s, _ in mine),
                "false_o_events": sum(Shape.O in s.confirmed for s, _ in mine),
                "false_frame_rate": round(
                    sum(s.false_frames for s, _ in mine) / sum(s.frames for s, _ in mine), 4
                ),
            }
            continue
        lat = [s.confirmed_at for s, _ in mine if s.confirmed_at is not None]
        # from the mark more than half in view (with a hand, it is raised into view some frames after it starts)
        from_view = [
            s.confirmed_at - (c.in_view - c.shown)
            for s, c in mine
            if s.confirmed_at is not None and c.in_view is not None
        ]
        slices: dict[str, dict[str, list[int]]] = defaultdict(lambda: defaultdict(lambda: [0, 0]))
        for s, c in mine:
            assert c.label is not None
            for name, value in (
                ("camera", "walking" if c.walking else "standing"),
                ("size_px", _bin(c.label.size, SIZE_BINS)),
                ("streak_px", _bin(c.blur_px, STREAK_BINS)),
                ("finger_near", str(c.label.finger_near).lower()),
                *((("filled", str(c.label.filled).lower()),) if shape is Shape.TRIANGLE else ()),
            ):
                cell = slices[name][value]
                cell[0] += s.confirmed_at is not None and s.confirmed_at < within
                cell[1] += 1
        wrong = (Shape.O,) if shape in DANGER_SHAPES else tuple(DANGER_SHAPES)
        out[shape.value] = {
            "clips": len(mine),
            "seen_within_1s": sum(x < within for x in lat),
            "seen": len(lat),
            "frames_to_confirm": {
                "p50": _pct(lat, 0.5),
                "p90": _pct(lat, 0.9),
                "max": max(lat) if lat else None,
            },
            "frames_from_view_to_confirm": {"p50": _pct(from_view, 0.5), "p90": _pct(from_view, 0.9)},
            "ms_to_confirm_p50": None if not lat else round(_pct(lat, 0.5) * 1000 / CLIP_FPS),  # type: ignore[operator]
            "frame_recall": round(
                sum(s.frames_found for s, _ in mine) / max(1, sum(s.frames_with_mark for s, _ in mine)), 3
            ),
            "wrong_class_events": sum(any(w in s.confirmed for w in wrong) for s, _ in mine),
            "danger_lifted_events": sum(s.lifted for s, _ in mine),
            "left_in_danger": sum(s.left_in_danger for s, _ in mine),
            "missed_in_every_frame": sum(s.confirmed_at is None and s.frames_found == 0 for s, _ in mine),
            "seen_within_1s_by": {
                name: {k: f"{v[0]}/{v[1]}" for k, v in sorted(cells.items())}
                for name, cells in slices.items()
            },
        }
    return out


def _tables(r: dict[str, Any]) -> str:
    fx = r["effects"]
    effects = ", ".join(
        [k.replace("_", " ") for k in ("hand", "rolling_shutter", "auto_exposure") if fx.get(k)]
        + ([f"a flickering lamp up to {fx['flicker']:g} ({fx['flicker_wave']})"] if fx.get("flicker") else [])
        + ([f"a lamp's reflection on the glossy card up to {fx['glare']:g} of white"] if fx.get("glare") else [])
    ) or "none"
    lines = [
        f"held-out clips, seed {r['seed']}: {r['clips_per_class']} clips per class of {r['frames_per_clip']} frames "
        f"at {CLIP_FPS:g} fps, the card up from frame {r['shown']}; OpenCV {r['opencv']}, 1 thread",
        f"detector settings: {' '.join(r['settings']) or 'the defaults'}",
        f"what a person and a real camera add: {effects}; the mark more than half in view from frames after the card "
        f"goes up p50 {r['frames_to_view']['p50']}, p90 {r['frames_to_view']['p90']}, max {r['frames_to_view']['max']}",
        "",
        f"{'class':9} {'clips':>5} {'seen<1s':>8} {'seen':>5} {'frames p50/p90/max':>19} {'ms p50':>7} "
        f"{'from view p50/p90':>17} {'frame recall':>12} {'never found':>11} {'wrong class':>11} {'lifted':>6}",
    ]
    for name in ("X", "TRIANGLE", "O"):
        c = r["per_class"].get(name)
        if c is None:
            continue
        f = c["frames_to_confirm"]
        spread = f"{f['p50']}/{f['p90']}/{f['max']}"
        from_view = f"{c['frames_from_view_to_confirm']['p50']}/{c['frames_from_view_to_confirm']['p90']}"
        lines.append(
            f"{name:9} {c['clips']:>5} {c['seen_within_1s']:>8} {c['seen']:>5} {spread:>19} "
            f"{c['ms_to_confirm_p50']!s:>7} {from_view:>17} {c['frame_recall']:>12.3f} {c['missed_in_every_frame']:>11} "
            f"{c['wrong_class_events']:>11} {c['danger_lifted_events'] if name != 'O' else '':>6}"
        )
    n = r["per_class"].get("none")
    if n:
        lines += [
            "",
            f"mark-free clips: {n['clips']}; confirmed X or triangle (a needless stop) in {n['false_danger_events']}, "
            f"confirmed O (a danger lifted by nothing) in {n['false_o_events']}; frames with a false mark "
            f"{100 * n['false_frame_rate']:.2f} %",
        ]
    lines.append("")
    for name in ("X", "TRIANGLE", "O"):
        c = r["per_class"].get(name)
        if c:
            by = "; ".join(
                f"{k}: " + ", ".join(f"{b} {v}" for b, v in cells.items())
                for k, cells in c["seen_within_1s_by"].items()
            )
            lines.append(f"{name} seen within 1 s by {by}")
    lines += [
        "",
        "the same detections under other confirmation windows (the service's: danger 1/3, O 3/4) and rules:",
    ]
    for kind, label, false in (
        ("safe", "O", "false O in mark-free clips"),
        ("danger", "X + triangle", "needless stops"),
    ):
        for window, w in r["windows"][kind].items():
            ms = "/".join(str(v) for v in w["ms_to_confirm_p50"])
            lines.append(
                f"  {label:12} {window:>4}: seen within 1 s {w['seen_within_1s']}/{w['clips']}, ms p50 {ms}, "
                f"{false} {w['false_events']}, wrong-class events {w['wrong_class_events']}"
            )
    for key, (label, _) in SAFE_RULES.items():
        w = r["windows"][key]
        lines.append(
            f"  {label}{SERVICE if w['service'] else ''}: danger lifted while its card was up in "
            f"{w['danger_lifted_events']} clips, danger seen within 1 s {w['danger_seen_within_1s']}, O seen within "
            f"1 s {w['o_seen_within_1s']} (p50 {w['o_ms_to_confirm_p50']} ms), O clips left in danger "
            f"{w['o_left_in_danger']}, mark-free clips with a confirmed O {w['false_o_events']}"
        )
    lines += [
        "",
        f"frames per CPU-second (detection only): {r['fps_per_cpu_second']}; clip streaks (the longest motion blur per "
        f"clip) p50 {r['streak_px']['p50']} px, p90 {r['streak_px']['p90']} px, max {r['streak_px']['max']} px",
    ]
    return "\n".join(lines)


def main(
    clips: Annotated[int, typer.Option(help="clips per class (X, O, triangle, mark-free)")] = 100,
    seed: Annotated[int, typer.Option(help="held-out generator seed")] = 2718,
    frames: Annotated[int, typer.Option(help="frames per clip (the card goes up at frame 6)")] = CLIP_FRAMES,
    hand: Annotated[
        bool, typer.Option(help="a hand raises the card into view, then holds it unsteadily")
    ] = False,
    rolling_shutter: Annotated[bool, typer.Option(help="rows read out top to bottom over 10-30 ms")] = False,
    auto_exposure: Annotated[
        bool, typer.Option(help="the camera's gain follows the frame's brightness")
    ] = False,
    flicker: Annotated[
        float, typer.Option(help="a flickering lamp lights the room, up to this depth of its light (bench/flicker.py)")
    ] = 0.0,
    flicker_wave: Annotated[str, typer.Option(help="with --flicker: sine (100/120 Hz) or pwm (an LED dimmer)")] = "sine",
    glare: Annotated[
        float, typer.Option(help="a lamp's reflection on the glossy card, up to this share of white (bench/glare.py)")
    ] = 0.0,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
    settings: Annotated[
        list[str] | None,
        typer.Option("--set", help="KEY=VALUE: a DetectorConfig setting, as the service's --detector takes it"),
    ] = None,
) -> None:
    try:
        config = parse_settings(settings or [])  # the service's own parsing (--detector, HRI_VISION_DETECTOR)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--set") from None
    if frames <= CLIP_SHOWN:
        raise typer.BadParameter(
            f"a clip needs more than its {CLIP_SHOWN} lead-in frames", param_hint="--frames"
        )
    if not 0.0 <= flicker <= 1.0 or flicker_wave not in WAVES:
        raise typer.BadParameter("--flicker is a depth from 0 to 1, --flicker-wave sine or pwm", param_hint="--flicker")
    if not 0.0 <= glare <= 10.0:
        raise typer.BadParameter("--glare is the highlight's peak, 0 to 10 times the sensor's white", param_hint="--glare")
    cv2.setNumThreads(1)
    gen = HeldOutGenerator(seed=seed)
    detector = MarkDetector(config)
    runs: list[tuple[HeldOutClip, list[list[Detection]]]] = []
    cpu = 0.0
    for i in range(clips * len(CLASSES)):
        clip = gen.clip(
            CLASSES[i % len(CLASSES)],
            frames=frames,
            hand=hand,
            rolling_shutter=rolling_shutter,
            auto_exposure=auto_exposure,
        )
        if flicker:  # one lamp a clip, its own draws (the scenes are the seed's own); its phase follows the frames
            lamp = draw_lamp(np.random.default_rng((seed, i)), flicker, flicker_wave)
            lamp_lit = [lit(f, lamp.gain(f.shape[0], k / CLIP_FPS)) for k, f in enumerate(clip.frames)]
            clip = dataclasses.replace(clip, frames=lamp_lit)
        if glare:  # one highlight a clip, its own draws too
            glossy = glare_clip(clip.frames, clip.boxes, np.random.default_rng((seed, i, 1)), glare, CLIP_FPS)
            clip = dataclasses.replace(clip, frames=glossy)
        found, spent = detect_clip(detector, clip)
        cpu += spent
        # the labels, not the frames (33 MB a clip)
        runs.append((dataclasses.replace(clip, frames=[]), found))
    rows = [(score_clip(c, f, confirm(f, Confirmation())), c) for c, f in runs]
    streaks = [c.blur_px for c, _ in runs]
    to_view = [c.in_view - c.shown for c, _ in runs if c.in_view is not None]
    result = {
        "seed": seed,
        "effects": {"hand": hand, "rolling_shutter": rolling_shutter, "auto_exposure": auto_exposure,
                    **({"flicker": flicker, "flicker_wave": flicker_wave} if flicker else {}),
                    **({"glare": glare} if glare else {})},
        "settings": list(settings or []),  # --set as given: what this run changed from the defaults
        "frames_to_view": {
            "p50": _pct(to_view, 0.5),
            "p90": _pct(to_view, 0.9),
            "max": max(to_view, default=None),
        },
        "clips_per_class": clips,
        "frames_per_clip": frames,
        "shown": rows[0][1].shown,
        "opencv": cv2.__version__,
        "per_class": summarise(rows),
        "windows": windows(runs),
        "fps_per_cpu_second": round(clips * len(CLASSES) * frames / cpu, 1) if cpu else None,
        "streak_px": {
            "p50": round(statistics.median(streaks), 1),
            "p90": round(sorted(streaks)[int(0.9 * len(streaks))], 1),
            "max": round(max(streaks), 1),
        },
    }
    print(json.dumps(result, indent=2) if as_json else _tables(result))


if __name__ == "__main__":
    typer.run(main)
