"""The robot's messages drawn into a Rerun recording: one `ViewLogger.log(topic, msg)` per message.

Entities (the `stamp` timeline is the message's own stamp):
- `camera/image` (the preview JPEG) and `camera/image/marks` (its boxes, labelled `X 0.91`);
- `robot/skeleton` (the stick figure from the joint angles) and `robot/joints` (its joint points);
- `joints/<name>` (one plot line per joint, radians);
- `state/situation` (0 safe, 1 danger), `state/posture` (sitting 0, standing 1, walking 2, moving 3,
  unknown -1);
- `log` (what was heard, seen, decided, moved and said, with reasons).
Only `rerun` is needed here: no Zenoh and no files, so the same code serves the live bus and a
recording.
"""

from __future__ import annotations

import base64

import rerun as rr
import rerun.blueprint as rrb

from schemas.messages import (
    Decision,
    Header,
    JointPositions,
    MarkObservation,
    MotionGoal,
    MotionState,
    Posture,
    SceneCommand,
    Situation,
    SpeechRequest,
    Verdict,
    VisionPreview,
    VoiceCommand,
)
from services.viewer.kinematics import figure

POSTURE_LEVEL: dict[Posture, int] = {Posture.SITTING: 0, Posture.STANDING: 1, Posture.WALKING: 2,
                                     Posture.MOVING: 3, Posture.UNKNOWN: -1}
SHAPE_COLOUR: dict[str, tuple[int, int, int]] = {"X": (230, 40, 40), "TRIANGLE": (255, 160, 0), "O": (40, 200, 40)}
TIMELINE = "stamp"


def blueprint() -> rrb.Blueprint:
    """Camera and robot side by side; joint plots, state over time and the text log beneath."""
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Spatial2DView(origin="camera", name="camera"),
                rrb.Spatial3DView(origin="robot", name="robot", eye_controls=rrb.EyeControls3D(
                    position=(0.42, -0.32, 0.30), look_target=(0.0, 0.0, 0.16), eye_up=(0.0, 0.0, 1.0))),
                rrb.TextLogView(origin="log", name="heard, decided, said"),
            ),
            rrb.Horizontal(
                rrb.TimeSeriesView(origin="joints", name="joint angles (rad)"),
                rrb.TimeSeriesView(origin="state", name="situation (1 danger) and posture"),
            ),
            row_shares=[3, 2],
        ),
        # Follow the newest data (live: as it comes); the time bar stays for scrubbing a recording.
        rrb.TimePanel(timeline=TIMELINE, play_state="following", state="collapsed"),
        collapse_panels=True,
    )


class ViewLogger:
    """Turns messages into Rerun entities on `rec`; keeps just enough state to log changes once."""

    def __init__(self, rec: rr.RecordingStream) -> None:
        self.rec = rec
        self._shapes: tuple[str, ...] | None = None
        self._posture: tuple[object, ...] | None = None
        self._goals: set[str] = set()
        self._series_named = False
        self.logged = 0
        # Situation and posture hold until the next change: steps, not slopes.
        for name in ("situation", "posture"):
            rec.log(f"state/{name}", rr.SeriesLines(names=name, interpolation_mode="stepafter"), static=True)

    def log(self, topic: str, msg: Header) -> None:
        """Log one message; `topic` is its key after `hri/<robot>/` (`vision/preview`)."""
        self.rec.set_time(TIMELINE, timestamp=msg.stamp)
        match msg:
            case VisionPreview():
                self._preview(msg)
            case JointPositions():
                self._joints(msg)
            case MarkObservation():
                self._marks(msg)
            case Decision():
                self._decision(msg)
            case MotionState():
                self._motion(msg)
            case VoiceCommand():
                what = msg.command.value if msg.command else "nothing"
                self._text(f'heard "{msg.text}" -> {what} ({msg.confidence:.2f}, {msg.engine})')
            case MotionGoal():
                if msg.goal_id not in self._goals:  # walk goals are renewed with the same id
                    self._goals.add(msg.goal_id)
                    self._text(f"goal {msg.action.value}")
            case SpeechRequest():
                self._text(f'says "{msg.text}"')
            case SceneCommand():
                self._text(f"(simulator) holds up {msg.shape.value if msg.shape else 'nothing'}", "DEBUG")
            case _:
                return
        self.logged += 1

    def _text(self, text: str, level: str = "INFO") -> None:
        self.rec.log("log", rr.TextLog(text, level=level))

    def _preview(self, p: VisionPreview) -> None:
        self.rec.log("camera/image", rr.EncodedImage(contents=base64.b64decode(p.jpeg), media_type="image/jpeg"))
        self.rec.log("camera/image/marks", rr.Boxes2D(
            array=[list(m.box) for m in p.marks], array_format=rr.Box2DFormat.XYWH,
            labels=[f"{m.shape.value} {m.confidence:.2f}" for m in p.marks],
            colors=[SHAPE_COLOUR[m.shape.value] for m in p.marks], show_labels=True))

    def _joints(self, j: JointPositions) -> None:
        angles = dict(zip(j.names, j.radians, strict=False))
        fig = figure(angles)
        self.rec.log("robot/skeleton", rr.LineStrips3D(fig.strips(), radii=0.004, colors=(90, 140, 230)))
        names, points = fig.joints()
        self.rec.log("robot/joints", rr.Points3D(points, radii=0.007, colors=(240, 240, 240)))
        if not self._series_named:
            self._series_named = True
            for name in j.names:
                self.rec.log(f"joints/{name}", rr.SeriesLines(names=name), static=True)
        for name, value in angles.items():
            self.rec.log(f"joints/{name}", rr.Scalars(value))

    def _marks(self, m: MarkObservation) -> None:
        shapes = tuple(sorted(k.shape.value for k in m.marks))
        if shapes != self._shapes:
            self._shapes = shapes
            seen = ", ".join(f"{k.shape.value} {k.confidence:.2f}" for k in m.marks) or "no mark"
            self._text(f"sees {seen}")

    def _decision(self, d: Decision) -> None:
        self.rec.log("state/situation", rr.Scalars(1.0 if d.situation is Situation.DANGER else 0.0))
        cause = d.command.value if d.command else "(mark)"
        action = f" -> {d.action.value}" if d.action else ""
        level = "WARN" if d.verdict in (Verdict.REFUSE, Verdict.ASK) else "INFO"
        self._text(f"{d.verdict.value.upper()} {cause}: {d.reason.value}{action}, situation {d.situation.value}",
                   level)

    def _motion(self, s: MotionState) -> None:
        self.rec.log("state/posture", rr.Scalars(float(POSTURE_LEVEL[s.posture])))
        sig = (s.posture, s.action, s.bus_ok)
        if sig != self._posture:
            self._posture = sig
            doing = f", doing {s.action.value}" if s.action else ""
            self._text(f"posture {s.posture.value}{doing}" + ("" if s.bus_ok else ", BUS FAULT"),
                       "INFO" if s.bus_ok else "ERROR")
