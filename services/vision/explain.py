"""Why a mark-like shape in an image was not reported: the detector's trace, read out for a person.

`python -m services.vision detect --explain IMAGE...` prints, for each image, the shapes the detector's own tests
read as an X, O or triangle (or the verifier found most like one) but did not report, each with the last test it
failed (`MarkDetector.trace`, the stages of `detector.STAGES`). A user holding a card up to their own camera learns
which rule of "What counts as a mark" (vision README) refused it: a filled triangle on a card with too much paper
round it, an O without a clear margin, a mark beside a word. Components no shape test read as a mark (noise,
clutter) are not listed. `python -m services.vision check` counts the same over a source's frames (`CardCheck`).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from schemas.messages import Shape
from services.vision.detector import STAGES, Box, Detection, MarkDetector, box_overlap, working_gray

REASONS: dict[str, str] = {
    "unnamed": "no shape test read it clearly and the learned verifier was not sure enough to name it: blurred, "
    "partly covered, washed out by a lamp's reflection on a glossy card, or drawn loosely",
    "card": "the card tests refused it: too little plain light paper right round it, other ink or a letter-sized "
    "shape beside it, or too faint against the paper",
    "O margin": "an O needs a clear margin of paper all round it (a tenth of its size): no finger or card edge "
    "right next to it",
    "hole": "its inside is not clean paper",
    "confidence": "the shape tests read it only weakly",
    "text line": "it stands in a line of text, as a letter of a word",
    "verifier": "the learned verifier did not take it for a mark",
}
"""The stages a shape can be refused at once a test read it as a mark, in words."""

FILLED_TRIANGLE = (
    "; a filled triangle is a mark only on a card that ends within about its width, in front of something darker "
    "than the paper (else it looks painted on a wall: draw an outline, trim the card, or accept more false stops "
    "with the detector setting filled_paper_round=0.9)"
)
"""Added where the verifier refused or did not name a triangle: the commonest such case (`bench/vision_cards.py`)."""

SAME_PLACE = 0.5
"""Two traced components whose boxes overlap by this share of the smaller are one shape (at two pyramid levels)."""


@dataclass(frozen=True)
class NearMiss:
    """A shape the detector's tests read as `shape` at `box` (input pixels) but did not report: `stage` is the
    furthest test it reached at any pyramid level."""

    shape: Shape
    box: Box
    stage: str

    @property
    def reason(self) -> str:
        return why(self.shape, self.stage)


def why(shape: Shape, stage: str) -> str:
    """The rule that refused a shape read as `shape` at `stage`, in words."""
    hint = FILLED_TRIANGLE if shape is Shape.TRIANGLE and stage in ("verifier", "unnamed") else ""
    return REASONS[stage] + hint


def explained(detector: MarkDetector, image: np.ndarray, limit: int = 5) -> tuple[list[Detection], list[NearMiss]]:
    """What `detector.detect(image)` reports (the same marks: the trace is that detection, recorded) and up to `limit`
    near misses, largest first, none over a reported mark; `image` BGR or grey, any size; boxes in its pixels."""
    gray, scale = working_gray(image, detector.config.max_side)  # as `MarkDetector.steps` scales a large frame
    found, traced = detector.trace(gray)
    shapes = sorted(
        (t for t in traced if t.shape is not None and t.stage in REASONS),
        key=lambda t: (-STAGES.index(t.stage), -t.box[2] * t.box[3]),  # the furthest stage first
    )
    out: list[NearMiss] = []
    for t in shapes:
        if any(box_overlap(t.box, d.box) >= SAME_PLACE for d in found):
            continue  # that place was reported
        if any(box_overlap(t.box, m.box) >= SAME_PLACE for m in out):
            continue  # the same shape at another pyramid level, which got no further
        assert t.shape is not None
        out.append(NearMiss(t.shape, t.box, t.stage))
    out.sort(key=lambda m: -m.box[2] * m.box[3])

    def scaled(box: Box) -> Box:
        return box if scale == 1.0 else tuple(round(v * scale) for v in box)  # type: ignore[return-value]

    return (
        [Detection(d.shape, d.confidence, scaled(d.box)) for d in found],
        [NearMiss(m.shape, scaled(m.box), m.stage) for m in out[:limit]],
    )


@dataclass
class CardCheck:
    """What `python -m services.vision check` saw over a run of frames: in how many each shape was reported, and
    each (shape, rule) a shape was refused by, in how many frames."""

    frames: int = 0
    reported: Counter[Shape] = field(default_factory=Counter)
    refused: Counter[tuple[Shape, str]] = field(default_factory=Counter)

    def add(self, found: list[Shape], misses: list[NearMiss]) -> None:
        """One frame: the shapes reported in it and its near misses (each shape and rule counted once a frame)."""
        self.frames += 1
        self.reported.update(set(found))
        self.refused.update({(m.shape, m.stage) for m in misses})

    def summary(self) -> list[str]:
        """Lines for a person: each shape reported, then each refusal with its rule in words, most frequent first."""
        if not self.frames:
            return ["no frame was read"]
        lines = [f"{self.frames} frame(s) looked at"]
        for shape in Shape:
            if shape in self.reported:
                lines.append(f"{shape.value}: reported in {self.reported[shape]} of {self.frames} frames")
        for (shape, stage), n in self.refused.most_common():
            lines.append(f"{shape.value}: read but not reported in {n} of {self.frames} frames: {why(shape, stage)}")
        if not self.reported and not self.refused:
            lines.append("nothing mark-like was seen: is the card in view, large enough (about 40 px), in focus, and "
                         "free of a lamp's reflection (tilt a glossy card until the reflection leaves the mark)?")
        return lines
