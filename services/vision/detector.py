"""Find X, O and triangle marks with contour shape features, checked last by a small learned verifier.

A mark is dark ink on a light card: a ring (O), a triangle outline (TRIANGLE) or two crossed bars (X).
Per frame, on a three-level pyramid (full resolution for small marks, half for small blurred ones, a
quarter for large ones):

1. grey image -> adaptive mean threshold (ink = darker than its neighbourhood by `offset`), which
   copes with uneven lighting;
2. connected components, filtered in one vectorised pass by size, aspect, fill ratio (a filled disc
   or square is too full), the frame edge, and a thin frame around each box that must be nearly
   free of ink (an integral-image test: a mark sits on a card, a blob of texture does not);
3. per surviving component: its outer contour and holes, then shape tests that survive rotation,
   perspective and blur -
   O: one hole, outer and hole both ellipses (small fit residual), concentric, ring-thick;
   TRIANGLE: one hole, outer and hole both fill their minimum enclosing triangle, concentric;
   X: no hole, exactly four deep convexity defects clustered at the centre, four arms of similar
   length, the solidity of a bar cross;
4. context: a clear light margin around the mark (0.3 of its extent, at most 2 % ink, clearly
   brighter than the ink, and plain: its grey-level spread small next to the ink's contrast); a
   ring's or triangle's hole empty and as bright as the margin (a large filled disc, hollowed by
   the local threshold, is not a ring); not a letter inside a word (two same-height neighbours on
   its baseline or cap line);
   a component in which they find no mark but that is dark ink on a light plain surround is a
   loose candidate: the learned verifier names its shape (or nothing), with stricter thresholds,
   and it goes on to the context tests like any other (this finds small, blurred and partly
   covered marks whose contours the tests above reject);
   a big full-resolution component in which they find no mark, dark on a light box and made of two
   clearly different grey levels (ink, and a lighter finger touching it), is cut to its darker level
   and its largest parts are judged like components (`split`; X and TRIANGLE only);
5. the learned verifier (`verifier.py`) must agree that the patch shows the claimed shape; and it
   may keep an X or triangle that some card tests refused (not for faint ink or a letter of its own word
   beside it: in its ink, on its card) if it is very sure (`card_rescue`): a missed danger mark is the worst miss;
6. a small network over the whole frame (`proposer.py`, `propose`) proposes marks where no component
   showed one; the verifier judges each like a loose candidate;
7. overlapping detections (the same mark at two pyramid levels) are merged, best confidence wins.

A filled disc, a square (outline or filled) or a filled triangle is not a mark. By construction an
isolated letter O / digit 0 or X with a clear margin is indistinguishable from a mark.
"""

from __future__ import annotations

import copy
import enum
import math
import re
from collections.abc import Generator, Iterable
from dataclasses import dataclass, fields, replace
from pathlib import Path

import cv2
import numpy as np

from schemas.messages import Mark, Shape
from services.vision.deflicker import MIN_DEPTH as DEFLICKER_DEPTH
from services.vision.deflicker import MIN_SHARE as DEFLICKER_SHARE
from services.vision.deflicker import deflicker
from services.vision.filled import FILLED_SHARE, LOOSE_TRIANGLE_FILL, ink_and_paper, paper_round, solid_share
from services.vision.proposer import MODEL_PATH as PROPOSER_PATH
from services.vision.proposer import Proposal, Proposer
from services.vision.verifier import CLASSES, MODEL_PATH, TRIANGLES_PATH, Verifier, claim, crops

Box = tuple[int, int, int, int]


class Step(enum.Enum):
    """Where a stepped detection (`MarkDetector.steps`) pauses: between two pieces of its work (each
    pyramid level, each judged component, each verifier call, the proposer)."""

    TICK = "tick"
    FINE = "fine"
    """with `danger_first`: every level but the finest is judged and verified, no danger mark among
    them; what is left is the finest level and the proposer (most of an ordinary frame's time)"""


Steps = Generator[Step, None, "list[Detection]"]
"""A frame's detection in steps: yields `Step`s, returns the detections (`finish` runs one to the end)."""


def finish(steps: Steps) -> list[Detection]:
    """Run a stepped detection to its end and return its detections."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


X_SOLIDITY = 0.5
"""The most an X's ink filled of its convex hull before round vision65b raised `DetectorConfig.x_solidity`."""
TWIN_PAPER = 0.1
"""`DetectorConfig.text_twin`: how near the grey round a two-letter word's other letter must be to the candidate's paper,
a share of (paper - ink). On a tuning look (stop 119) the other letter of every turned two-letter word on a card was
within 0.05, and every mark the looser size alone lost had its neighbour on another paper, 0.16 to 0.33 away."""
TWIN_INK = 0.15
"""... and how near its mean grey must be to the candidate's ink, a share of (paper - ink): a word's letters differ by
their strokes' width under blur (up to 0.14 on the look), a finger over the card from the ink by more (0.24)."""
TWIN_CONTRAST = 40.0
"""... the least (paper - ink), grey levels, for which the looser twin is asked: a faint, blurred pair (27 levels on
the look: a hand-drawn O and a finger's shadow) is no readable word; the look's words were 87 or more."""
TWIN_SIZE = 10
"""... and the least upright box side, pixels at its level, of the candidate: specks of noise two by two are no word,
and the text-line test also judges the small components under a proposal (`_in_text`)."""


@dataclass(frozen=True)
class DetectorConfig:
    levels: tuple[tuple[int, ...], ...] = ((1, 31), (2, 31), (4, 31), (6, 31))
    """(downscale factor, adaptive-threshold window in pixels at that scale[, largest component judged
    there, pixels at that scale]): full resolution for small marks, coarser levels for larger ones
    (whose strokes are wider than the full-resolution window, and whose motion blur shrinks with the
    scale). Half resolution: a small mark smeared by motion blur or broken by noise into pieces at full
    resolution is often one component at half (tuning seeds 555, 1234, 99, 31337: recall +1.6 X, +1.8
    O, +1.3 TRIANGLE points, one more false triangle in 4,000 frames, 16 % slower); it judged only
    components up to 50 px until round vision16. A sixth (107x80 for a 640x480 frame: marks from about
    70 px) since round vision16: a big mark smeared by 15-20 px of motion blur, or with strokes wider
    than the quarter level's window, is whole and crisp there. The two together, on the same four seeds
    with varied hands (`--hand-variety 0.5`): 567 -> 517 missed marks of 3,000, one more false X,
    about 17 % slower (the vision README, round vision16). An eighth instead of a sixth found as many,
    but there a letter beside the mark is too coarse a blob for the word test."""
    offset: float = 12.0  # ink is at least this much darker than its local mean (grey levels)
    min_size: int = 12  # smallest mark width/height in pixels at a scale
    full_res_max: int = 0
    """components bigger than this at full resolution are left to the coarser levels (0: no limit),
    where they are judged on a sixteenth of the pixels: a speed knob. 160 makes detection about 20 %
    faster and costs 0.5-1 % of O and triangle recall on the tuning generator (2-3 % held-out)."""
    max_aspect: float = 3.5  # longest/shortest side of the component's box (strong tilt)
    x_solidity: float = 0.6
    """an X's ink fills at most this share of its outline's convex hull (and at least 0.18): bars up to about a quarter
    of their length wide (tape strips, a broad marker). `X_SOLIDITY`, 0.5, until round vision65b: an X of bars wider than
    about 0.18 of their length was left to the verifier as a loose candidate and needed its loose bar (on fresh seeds
    9 more X found of 2,000 held-out and blind, for 2 more blind false X in 4,000 frames)"""
    x_solidity_veto: bool = False
    """whether an X claimed only above `X_SOLIDITY` (its ink filling more than half its hull), refused by the card tests
    or as a letter of a text line, keeps the proposer out of its place as every other refused component does. Off (round
    vision65b): it leaves the place to the proposer, as it did when it was not claimed; round vision65's 0.6 with it on
    lost a small X under 20 px of motion blur, thickened by its blur, refused on its card, which then vetoed the proposal
    that found it"""
    filled_solidity: float = 0.93
    """a filled triangle (no hole) fills at least this share of its outline's convex hull ..."""
    filled_fill: float = 0.85
    """... and of its minimum enclosing triangle (its shape confidence is 0.5 there, 1 at a full fill)"""
    surround: float = 0.3  # how far around a mark the card is inspected, as a fraction of its size
    border: float = 0.05  # the narrowest card border next to a mark that is judged, fraction of its size
    min_band_paper: float = 0.6  # share of that border band that must be paper
    min_hole_contrast: float = 0.7  # hole brightness above ink, relative to the margin's
    max_surround_ink: float = 0.06  # share of the card near the mark that other ink may cover ...
    clutter_radius: float = 0.15  # ... within this fraction of its size
    safe_margin: float = 0.1  # the O also needs this clear margin, fraction of size (0: off) ...
    safe_max_ink: float = 0.02  # ... with at most this share of ink in it (a false O lifts a danger)
    safe_margin_card: bool = True
    """an O the clear margin above refuses is judged again on its card, as the card tests judge marks
    (`_card_margin`): the ink that counts against it is other ink the card encloses, at most `safe_card_ink` of the
    card's part of the ring, not a card edge or a finger reaching in from beyond the card. Rounds vision63 and 63b
    (stop 109; round vision63, commit 90eed45, judged on the card alone, with `safe_max_ink` as its share) found 5
    points of held-out O recall and 5 more false O; on by default since round vision63c (stop 110), with its two
    guards `safe_card_extent` and `safe_card_sure`: on fresh seeds held-out missed O 168 -> 112 of 1,000 with the same
    26 false O in 4,000 frames, blind 88 -> 76 with the same 6 (vision README)."""
    safe_card_ink: float = 0.06
    safe_card_extent: float = 20.0
    """with `safe_margin_card`: an O is judged on its card only if its extent (the square root of its outline's hull
    area, in its pyramid level's pixels) is at least this: for a smaller O the margin is a ring of 1-3 px, too narrow
    to say what is card and what is not, and a finger or a card's edge there excuses whatever ink touches it. Round
    vision63c (stop 110: a 15 px red ring beside a finger, spent blind seed 1249). 0: any size."""
    safe_card_sure: float = 0.95
    """with `safe_margin_card`: an O the strict margin refused and its card spared is kept only if the verifier gives
    it at least this probability of an O (a claimed O needs 0.8 otherwise, the verifier's `thresholds`; a loose one
    is named O only at 0.95 anyway). Judged on less context, the safe mark asks for surer shape evidence, as a proposed
    O does (`propose_sure_thresholds`). 0: no more than any O; without the verifier such an O is refused. Round
    vision63c (stop 110)."""
    letter_gap: float = 0.25  # a letter-sized shape on the card this close (fraction of size): a word
    text_max_f: int = 8
    """the text-line test runs on pyramid levels of downscale up to this: every level since round
    vision13 (2 before: a big printed O or X in a word, its letters too big for the finer levels, passed
    at the quarter level; 4 until round vision16's sixth level: at 4 with that level,
    bench/vision_words.py seed 555 gave 28 frames with a false mark among 300 with words, against 5
    before the level and 6 with it and the test there)"""
    text_turned: bool = True
    """text line: also look for a line of letters turned at any angle (to each letter-sized neighbour):
    upright words were no mark, but turned by 10 degrees (a camera's roll, a sign hung askew) most big
    printed words gave a false O or X. Round vision20: on fresh held-out seeds false marks 94 -> 89 with
    one more missed O in 4,000 frames; two-letter words turned by 15 degrees or more are still a mark"""
    text_whole: str = "turned"
    """text line: count as a neighbouring letter only a component wholly inside the frame (at its level)
    on the turned lines ("turned") or on every line ("all"; "": off); one that runs out of the frame is
    the background, a person or an object, not the next letter (as for the word test beside a mark,
    `_letter_beside`). The demo scene's X card was refused at the coarser levels by the turned test, for
    the rocket and the face cut by the frame's edges. "turned" since round vision25c; "all" (round
    vision25b) also let words running out of the frame through: 3 more held-out frames with a false mark"""
    text_paper: float = 0.7
    """text line: the share of a thin ring round a neighbouring letter that must be paper (lighter than
    half-way from ink to paper); the dark background beyond a card's edge is not a letter (0: off)"""
    text_twin: float = 0.0
    """text line, turned: a lone neighbour also makes a two-letter word (NO, OK, XO on a card held up at any angle)
    where its upright box's longest side is within this share of the candidate's, not only the tenth a twin must be
    within, if it is printed on the candidate's own paper in its ink: the median grey of a thin ring round it within
    `TWIN_PAPER` x (paper - ink) of the candidate's paper, its mean grey within `TWIN_INK` x (paper - ink) of the
    candidate's ink, in a readable pair (`TWIN_CONTRAST`, `TWIN_SIZE`) (0: off). A letter's upright box turns with it,
    and O, K and N differ in width: a turned two-letter word's letters are seldom a tenth apart. Off: rounds vision73
    and 73b (stop 119) did not land it; at 0.3, 32 -> 10 tuning probe frames of 400 with a word card held up had a
    false mark, but on held-out frames 23 -> 20 false marks on words, where the rule asked for 19"""
    letter_ink: float = 0.0
    """... printed in the same ink: its mean grey within max(8, letter_ink x (paper - ink)) of the mark's
    (0: any shape as dark as `dark` counts, however much darker than the mark)"""
    letter_other_ink: float = 0.25
    """where the letter test refuses an X or triangle, and none of the letter-sized shapes beside it is printed in the
    mark's ink by `letter_ink`'s measure at this value, the refusal is "beside" instead of "letter" (another card's
    print, a sign, a bracket in another ink): a reason `card_rescue_from` may name, unlike "letter", whose same-ink
    neighbour makes the mark a letter of a word (0: off, every refusal is "letter"; rounds vision36b and 36c: with
    `letter_card`, the default since 36c, 5 more held-out X and triangles in 8,000 frames, no false mark added)"""
    letter_card: bool = True
    """... likewise "beside" where none of those shapes is printed on the mark's own card (the paper round it is
    not the light region the mark's band touches: another card, a page or a face beyond the card's edge); with
    `letter_other_ink` too, a letter must be both: "XK" in one ink on one card stays a word (rounds vision36b, 36c)"""
    letter_card_paper: float = 0.25
    """for `letter_card`, the mark's card is only the light region within this share of (paper - ink) of the paper's
    grey, not everything lighter than half-way (0: off): a lighter or darker page or wall that joins the card at
    its edge is then not the card (the default since round vision36e: with round vision36d's runs, 19 more held-out
    X and triangles in 8,000 frames, no false mark added, no slower)"""
    max_contrast_ratio: float = 0.72  # ink mean / surround mean must be below this
    danger_contrast_ratio: float = 0.0
    """the same limit for an X or a TRIANGLE (0: `max_contrast_ratio`), so that light ink (pink, orange, pale tape, in
    grey) can stop the robot while an O, which lifts a danger, keeps the stricter limit (round vision59b); loose
    candidates reach the verifier under the higher of the two, and the card tests apply the named shape's"""
    min_contrast: float = 25.0
    """paper (the band's median) minus ink mean, grey levels: print on paper, not a shadow. 35 until
    this round: under dim light (exposure 0.35-0.7) or with pale ink a printed mark has 25-35 levels,
    and 25 found 0.7-1.1 % more marks on four tuning seeds with no more false marks there"""
    max_margin_texture: float = 0.35  # margin grey std / (margin - ink): a card is plain, gravel is not
    texture_window: float = 0.0
    """the card test's plainness measured against the card's own local mean (0: off): where the card near a mark
    spreads more than `max_margin_texture` allows, the spread is measured again after each card pixel's mean over a
    window of this share of the mark's extent (card pixels only) is taken out, so that light that changes smoothly
    across the card - a lamp's highlight on a glossy card, a strong gradient - is not taken for texture, while gravel's
    grain, finer than the window, still is. It can only pass a card the plain measure refused. Round vision71 (stop
    117): under `bench/glare.py`'s highlight the texture test refused a tenth of the lost marks' cards; on held-out
    frames the window found 39 of 1,167 marks lost under the highlight but added a false O there, so it is off."""
    danger_texture_window: float = 0.5
    """the same window for an X or a TRIANGLE only (0: `texture_window`), so that a highlighted danger mark can stop the
    robot while an O, which lifts a danger, is not kept by it (as `danger_contrast_ratio` does for light ink; an O has
    its own window, `safe_texture_window`, guarded by the verifier).
    Round vision71b (stop 117) was refused on a speed condition measured across sittings; round vision71c (stop 118)
    judged it again on fresh seeds, timed in one sitting: on held-out frames 31 of 726 X and triangles a highlight hid
    found (X 239 -> 219), 6 of 307 marks without it, no false O added, 3 more false X or triangles in 4,000 frames
    (6 under the highlight), the same speed: the default since stop 118."""
    safe_texture_window: float = 0.5
    """the same window for an O's card, asked only where the plain measure refused it as texture (0: off); an O kept
    so must also have the verifier's `safe_card_sure`, like an O its card spared at the clear margin: round vision71's
    window on every card made one false O more under a highlight, and a false O lifts a danger. Round vision72 (stop
    118): on fresh held-out frames at a highlight's peak of white 15 of 427 hidden O found, 1 of 294 marks without
    it, no false mark added anywhere, the same speed: the default since stop 118."""
    min_confidence: float = 0.5
    loose_confidence: float = 0.5
    """the confidence a loose candidate needs once the verifier has named it, its probability for that shape taking
    the place of the shape tests' fit (`min_confidence` for those). At 0.5 it is the bar a named loose X needs in
    effect, above the verifier's own loose X bar (`loose_thresholds` X, 0.1, where the verifier's two networks
    agree): round vision58 found that 0.1 could not act. 0 leaves naming to the verifier's loose thresholds. The
    verifier names a loose O or TRIANGLE only at 0.95 and 0.9 (and the second network a triangle at
    `hand_triangle_loose`, 0.8 when on), so at 0.5 it changes nothing for them."""
    frame_margin: float = 0.04  # pre-test: a thin frame this far around a component's box ...
    frame_max_ink: float = 0.5  # ... may be at most this much ink
    max_side: int = 640  # larger frames are scaled down to this longest side first
    overlap: float = 0.5  # intersection / smaller box above which two detections are one mark
    loose: bool = True
    """components in which the shape tests find no mark (a small or blurred ring whose hole closed, a
    triangle with a finger over a corner) still go to the verifier when they are dark on a light
    surround (`loose_contrast`, `loose_texture`); it names their shape, with the stricter
    `Verifier.loose_thresholds`, and the card tests judge them as any other mark. Needs `verify`."""
    loose_contrast: float = 35.0
    """the frame around the box at least this much lighter than the ink (45 with the HOG verifier: the
    CNN rejects false candidates well enough for 35 and 0.7, chosen on tuning seeds 555 and 1234)"""
    loose_texture: float = 0.7  # and its grey-level spread at most this share of that contrast (0.5)
    loose_max_size: int = 96
    """at full resolution only components up to this size are loose candidates: a bigger mark is
    also a component of the quarter-scale level, where its patch costs a sixteenth"""
    card_rescue: float = 0.95
    """an X or TRIANGLE (claimed by the shape tests, or a loose candidate the verifier named) that one of
    the card tests in `card_rescue_from` refused is still kept if the verifier gives its shape at least
    this probability (0: off). Only danger marks: a false one stops the robot, a missed one lets it
    walk on; an O is never rescued (a false O lifts a danger)."""
    card_rescue_from: tuple[str, ...] = ("band", "texture", "ink", "ratio", "beside")
    """the card tests (`_on_card`'s reasons) the verifier may overrule: not "faint" (under
    `min_contrast` a cross is a shadow or a crease; the network sees contrast-stretched crops and
    cannot tell) and not "letter" (a letter of a word; a rescued letter was the false X the tuning
    frames showed, and the X of "XK" in round vision36), nor a letter inside a line of text. "beside" (a letter-test
    refusal with no letter of the mark's word beside it: `letter_other_ink`, `letter_card`) is named since round
    vision36c"""
    split: str = "grey,loose,edge"
    """separate a mark from a finger it touches ("" turns it off): a big component in which the shape
    tests find no mark, dark on a light box, made of two clearly different grey levels (ink, and a
    lighter finger: skin), is cut into the parts of its darker level, and each of its largest parts goes
    through the shape, card and verifier path like any other component; with "loose", a part the shape
    tests read nothing in may also be named by the verifier like a loose candidate. Only an X or a
    TRIANGLE is taken from a part (an O touched by a finger fails its clear margin anyway, and a false
    O can lift a danger). With "edge", a component cut by the frame edge (a mark joined to a finger that
    runs on out of the frame: the hand holding the card is out of view) is split too; it is never
    judged whole, and parts that touch the frame edge are not judged."""
    split_contrast: float = 30.0  # the two grey levels' means at least this far apart
    split_share: tuple[float, float] = (0.05, 0.03)
    """grey split: the dark and the light part must each be at least this share of the component (a
    finger is often binarised only along its outline, a small share)"""
    split_explained: float = 0.7  # grey split: at least this share of the grey-level variance explained
    split_surround: float = 40.0  # its box's mean grey at least this much lighter than its own
    split_levels: tuple[int, ...] = (1,)  # the pyramid levels (downscale factors) it is tried at
    split_min: int = 100  # smallest component (longest side, pixels at its level) that is split
    split_shrink: float = 1.0  # a part the verifier is to name must be at most this share of the component
    split_parts: int = 3  # the largest parts left are judged, at most this many
    propose: float = 0.3
    """the learned proposer (proposer.py) looks at the whole frame for marks no component showed: a
    proposal whose heatmap peak reaches this (0: off) and that overlaps no detection, no component the
    context tests refused and no letter in a line of text is shown to the verifier as a loose candidate,
    and kept if the verifier gives the proposed shape at least its `propose_thresholds`. The card tests
    cannot judge it (it has no component). Needs `verify`. On since round vision19 (its int8 model): on
    fresh held-out seeds it found 30 % of the X and triangles missed without it, for 10 more false ones in
    4,000 frames, at 113.9 frames per CPU-second against 133.8 (vision README, "The learned proposer")."""
    faint_veto: bool = True
    """a component the card tests refused as "faint" (under `min_contrast` between its ink and the band just outside it)
    vetoes the proposer over it, as every component the context tests refused does. Off (round vision64): such a
    component is no ink on paper, so it says nothing of a mark's context; it is often a mark's own part - a thick
    ring's inner edge, which the finest level's local threshold cuts from the stroke's middle - and then it kept out a
    proposal of that very mark (a big O the verifier is sure of, its outer edge merged with a finger). Round
    vision64 (`faint_veto=0`) did not land: a faint component can also be the whole of a faint mark (an X under
    `min_contrast`, a shadow or a crease by the card tests), and then the veto keeps the proposer from overruling the
    contrast test."""
    faint_veto_contrast: float = -255.0
    """with `faint_veto`: a component refused as faint vetoes the proposer only if the band just outside it is at
    least this many grey levels lighter than its ink (-255: every one). Round vision64b's variant 1: a faint mark is
    a little darker than its paper, while a component no darker than the band round it lies within ink - a thick
    stroke's inner edge, the stroke's own ink for its band (tuning seed 7234's two big O: 3 grey levels lighter than
    its band). Rounds vision64b-64c did not land it: on fresh seeds it found 5 more held-out and 2 more blind marks of
    6,000 each and 5 more of 900 held-out clips, for 1 more blind false triangle - real, and too small for their rules
    (vision README)."""
    propose_thresholds: tuple[float, ...] = (0.5, 0.99, 0.9)
    """the verifier's probability a proposed X, O and TRIANGLE needs (a false O lifts a danger), chosen on
    tuning seeds 99 + 555 (round vision18b); X 0.3 from round vision23g (0.7 before), whose verifier gives a
    proposal, like any loose candidate, the lower of two networks' X (`ensemble.py`); 0.5 since round vision45c,
    whose second network learned crossing strokes (a cable in a loop, two taped lines) as not an X: chosen on tuning
    seed 7156 and crossing-probe seed 78 by the round's rule. Round vision45d's 0.3 with that veto found 6 more of 4,000
    held-out frames' X for 3 more false X, but 4 more blind X for 7 more false X: not taken"""
    propose_sure: tuple[float, ...] = (0.7, 0.6, 0.0)
    """X, O and TRIANGLE: a proposal of that shape whose heatmap peak reaches this (0: never) is kept at the lower of
    `propose_thresholds` and `propose_sure_thresholds`: two learned judges agree, the proposer from the whole frame
    at half size and the verifier from the three crops. O at 0.6 since round vision47b (bar 0.95, with
    `propose_o_clear`; vision README): on fresh seeds 16 of 183 missed held-out O and 11 of 133 missed blind O found
    in 4,000 frames each, no false mark added, no confirmed false O added on held-out clips. Rounds vision42-42c
    (bars 0.75 and 0.85, no middle test) found more, and false O on the blind generator. X at 0.7 (bar 0.01) since
    round vision56, a trade: on fresh seeds 11 of 55 missed held-out X found for 2 more false X, 8 of 50 blind for 4
    more (round vision42, before the proposer's crossing veto and the star test: held-out 5 for 1, blind 2 for 5).
    TRIANGLE off: peaks of 0.6-0.8 also came on filled arrows on white labels (the arrow probe)"""
    propose_sure_thresholds: tuple[float, ...] = (0.01, 0.95, 0.05)
    """the verifier's probability a proposed X, O and TRIANGLE needs when its peak reaches `propose_sure` (O 0.95 since
    round vision47b: the lowest bar that kept none of the false O the sure peak had kept on six blind seeds and
    round vision47's tuning frames; X and TRIANGLE the last bars rounds vision42-42c tried)"""
    propose_o_clear: float = 0.05
    """a proposed O kept only at its sure bar (`propose_sure`: its verifier probability is under
    `propose_thresholds`' O) must have a clear middle: at most this share of the middle of its box (an ellipse of
    `propose_o_middle` x its width and height) darker than half-way from its ring's ink to the middle's paper
    (`middle_ink`; 0: not asked). An O mark's hole is blank card; a clock face has hands and a hub there, a
    prohibition sign its bar, a fingertip its nail: round things whose outline a proposer and a verifier may take
    for an O. A proposal has no component, so the O's own clear-margin test cannot judge it. Round vision47 (bar
    0.75): every true O the sure peak kept on tuning and six blind seeds had a blank middle (0.00), a fingertip
    0.13 and a clock face 0.09; at round vision47b's bar 0.95 the bar alone refused those seen, so this is a guard
    for a clock or a fingertip the verifier is surer of."""
    propose_o_middle: float = 0.4
    """the middle `propose_o_clear` looks at, as a share of the proposal box's width and height (an O's hole is
    0.6-0.8 of its width with the tuning generator's strokes; the rest allows for the box's own error)"""
    propose_t_fill: float = 0.7
    """a proposed TRIANGLE is refused where the ink at its middle is one solid blob with no corners: no hole, inside
    the box, filling less than this share of its minimum enclosing triangle (a disc 0.6, a triangle about 1; 0: off)
    and with an outline as round as an ellipse (`propose_t_round`; `middle_blob`). A dot sticker, a button or a
    coloured disc on a small card is a small solid blob the proposer and the verifier may take for a filled triangle;
    the component's own shape test (`filled_fill`) had already refused it. On since round vision48 (vision README):
    on two fresh blind seeds 22 of 63 false triangles gone (false-mark frames 45 -> 32 of 1,000), no mark lost; on the
    held-out generator's frames, which have no such dots, nothing changed."""
    propose_t_round: float = 0.06
    """the largest `_ellipse_residual` of that blob's outline that counts as round (a disc about 0.02-0.04, a filled
    triangle about 0.1)"""
    o_clear: float = 0.05
    """an O the verifier is not sure of (confidence under `o_clear_sure`) is refused where more than this share of the
    middle of its box (`propose_o_middle`) is ink (`middle_ink`): an O mark's hole is blank card, a clock's hands and
    hub, a face's eyes or a sign's bar are not (0: off). On since round vision49 (vision README): on two fresh blind
    seeds false O 17 -> 12, on two fresh held-out seeds 14 -> 12, for one more missed held-out O in 1,000."""
    o_clear_sure: float = 0.95
    """the confidence from which an O is reported whatever its middle holds (`o_clear`)"""
    o_islands: float = 0.01
    """an O is refused, however sure the verifier is, where separate blobs of ink lie wholly inside the middle of its
    box (`hole_islands`: touching neither its ring nor anything beyond the middle) and cover more than this share of
    its box: a face's eyes and mouth inside the outline of a head. An O mark's hole is blank card; a fingertip
    reaching into it comes in across the ring, so it is not a separate blob. 0: off. On since round vision52 (vision
    README): on two fresh blind seeds false O 5 -> 4, nothing lost; on two fresh held-out seeds every count the same.
    Chosen where the true O of three tuning seeds had islands covering at most 0.53 % of the box and the faces taken
    for an O on two diagnostic blind seeds 1.44 % or more."""
    open_side: float = 0.75
    """a loose candidate without a hole that the verifier (or the second network) names a TRIANGLE is refused where
    one side of its minimum enclosing triangle is open: drawn along less than this share (the cover of `open_side`,
    the function) and, in its middle, about as light as the paper round it (shade under `open_side_shade`). Two
    strokes meeting at an angle have a triangle for a hull: a clock's two hands, a check mark, a chevron; the blind
    generator's clock hands were its commonest false triangles. A filled triangle draws every side; an outline
    broken by a finger or blurred faint has the finger or the faint stroke across its open side. 0: off. On since
    round vision50 (vision README): on two fresh blind seeds false triangles 44 -> 17 and false-mark frames 33 -> 19
    of 1,000, one more triangle found; on two fresh held-out seeds every count the same."""
    open_side_shade: float = 0.15
    """the darkest an open side's middle may be, from the paper round the outline (0) to the outline's ink (1), for
    `open_side` to refuse the candidate"""
    propose_open_side: float = 0.6
    """the same of a proposed TRIANGLE (`open_side`, `open_side_shade`), judged on the largest blob of ink inside its box
    without a hole (`box_outline`; a proposal has no component of its own): refused where one side is drawn along less
    than this share and is as light as the paper (a clock's hands, a chevron or a check mark on a card). 0: off. On
    since round vision50b (vision README): on two fresh blind seeds false triangles 12 -> 9 and false-mark frames 15 ->
    13 of 1,000; on two fresh held-out seeds every count the same."""
    propose_open_margin: float = 0.5
    """the paper round a proposed TRIANGLE's box, as a share of its size, in which `propose_open_side` looks for its ink
    (`box_outline`): a blob that runs on past that region is not judged. The proposer's box often sits tight on, or
    inside, a clock's hands or a check mark, whose strokes then run past a tenth (0.1, the margin before round
    vision54). Rounds vision53-54 (vision README): on six fresh blind seeds false triangles 36 -> 25, no mark lost,
    every held-out count the same"""
    star_depth: float = 0.1
    """an X or a TRIANGLE (a component's or a proposal's) is refused where the largest blob of ink in its box (holes
    allowed; one running on past the box, joined to a finger or a card's edge, is not judged) has five or more notches
    at least this share of its extent deep, spread round it so that no two neighbours lie more than `star_spread`
    times an even spacing apart, the nearest `star_inner` or more of the way out (`notches`): a five-pointed star,
    outlined or filled, a sticker or a sign on a card. An X has four such notches and a triangle none; the blind
    generator's stars were taken for both. 0: off. On since round vision51 (vision README): on two fresh blind seeds
    false X and triangles 28 -> 24 and false-mark frames 22 -> 18 of 1,000, nothing lost; on two fresh held-out seeds
    every count the same; about 3 % of the speed (one call for about every second held-out frame, 0.35 ms p50)."""
    star_spread: float = 1.6
    """the widest angle between two neighbouring notches (`star_depth`), as a multiple of 360 degrees over their
    number, for the notches to count as a star's"""
    star_inner: float = 0.33
    """the nearest of those notches must lie at least this share of the blob's reach from its centre: a star's notches
    lie about half-way out (0.34-0.49 on the blind generator's stars), an X's where its strokes cross, near the centre,
    even where a finger joined to a stroke adds a fifth notch (0.07-0.22 on the tuning generator's)"""
    propose_x_span: float = 0.0
    """a proposed X is refused where its strokes run on as a crossing's do (`propose_x_exits` of them): the ink at
    its middle belongs to a component (at the finest pyramid level) whose longest side is at least this many times
    the proposal's, and that component leaves a circle round the proposal (radius `propose_x_ring` times its
    longest side) in at least `propose_x_exits` separate narrow strokes. Two cables, tape lines or pen strokes
    crossing, or a cable lying in a loop, look like an X where they cross but run on past it in four directions; a
    mark joined to a finger, a passing cable or a dark surround leaves in one or two, or over a wide arc (stop 78's
    crossing probe; round vision44, the size alone, lost X of those kinds). 0: off. Off since rounds vision44-44c
    (vision README): at 2 with `propose_x_cover` 0.25 it took the probe's frames with a false X from 92 to 32 of 600
    and the blind generator's false X from 43 to 29, but lost 10 more held-out X (37 -> 47 of 4,000 frames)"""
    propose_x_exits: int = 3
    propose_x_ring: float = 0.9
    propose_x_arc: float = 0.12
    """the widest a stroke leaving the circle may be, as a share of the circle (a dark surround is wider)"""
    propose_x_cover: float = 0.0
    """the most of the circle the component may cover, and the strokes leaving it be at most twice
    `propose_x_exits` (0: no limit): crossing strokes leave a few narrow runs on paper, while a dark or textured
    background that a small card's X touches covers much of the circle, broken into many runs (round vision44c)"""
    hand_triangle: float = 0.8
    """a second network's word on triangles (`verifier_triangles.onnx`: the verifier's recipe trained with 40 % of
    the triangles drawn by hand): a TRIANGLE the shape tests claimed and the card tests passed, which the verifier
    refused, is kept if the second network gives TRIANGLE at least this probability (0: not asked). It adds only
    triangles: a missed one lets the robot walk on, a false one stops it. The verifier refused a third of the
    filled triangles drawn by hand (`bench/vision_stages.py --hand-drawn 1`), having learnt exact ones. On since
    round vision34 (the vision README): on fresh held-out seeds 30 of 160 missed triangles found for 4 more false
    ones in 4,000 frames; on the blind generator 36 of 236 for none; about 3 % of the speed. Needs `verify`."""
    filled_paper_round: float = 0.0
    """a filled TRIANGLE that both networks refused - one the shape and card tests claimed, or a loose candidate the
    verifier likeliest calls a triangle that fills `filled.LOOSE_TRIANGLE_FILL` of its enclosing triangle, which the
    card tests then judge - is kept where at least this share of a ring round it is paper (`filled.paper_round`; 0:
    off). The verifier, seeing four times the mark, takes a filled triangle on a sheet much wider than itself, or on a
    card that runs out of the frame, for one painted on a wall; with this on, a danger mark on plain paper stops the
    robot whatever the paper's extent. Off: round vision61 (the vision README) found 12 of 184 missed tuning triangles
    for 6 false ones and failed its gates (letters A and V, warning signs, play buttons and arrow heads have paper
    round them too); `bench/vision_cards.py`'s filled triangles on wide cards and on white before white it finds."""
    hand_triangle_loose: float = 0.0
    """the second network's word on a loose candidate too (0: not asked): one the verifier did not name, to which it
    gives TRIANGLE at least `hand_triangle_floor`, is named a TRIANGLE if the second network gives TRIANGLE at least
    this probability; the card tests then judge it like any loose candidate (with no rescue: the verifier did not
    vouch for it). Off: round vision35 (the vision README) found 9 more triangles in 4,000 held-out frames for 9
    more false ones, and 3 for 17 on the blind generator; round vision35b, with `hand_triangle_solid`, 6 held-out
    for none, but 1 for 24 on the blind generator; round vision55, after the refusals of rounds vision48-54, 11 more
    on tuning frames for 4 more false ones, and failed its tuning stage."""
    hand_triangle_floor: float = 0.3
    """the verifier's TRIANGLE probability a loose candidate needs before the second network is asked about it
    (`hand_triangle_loose`): most loose candidates are clutter the verifier is sure of, and asking about each
    cost about 6 % of the speed in round vision34's probe"""
    hand_triangle_solid: float = 0.8
    """a loose candidate is asked about (`hand_triangle_loose`) only if it has a hole or fills less than this share
    of its convex hull: round vision35's new false triangles on tuning frames were solid dark shapes off a card,
    clutter the second network took for filled triangles (round vision35b); 1 asks about every one, as round
    vision35 did"""
    hand_triangle_model: str = ""
    """the second network's ONNX file ("": the committed `verifier_triangles.onnx`), for judging a retrained one
    with the benches' `--set` (`python -m services.vision.training --out ...`; round vision40); a file that is no
    verifier for this code's inputs is refused when the detector is made"""
    verifier_model: str = ""
    """the verifier's ONNX file ("": the committed `verifier.onnx`), for judging a retrained or re-joined one with the
    benches' `--set` (`python -m services.vision.ensemble ... --out ...`; round vision45); a file that is no verifier
    for this code's inputs is refused when the detector is made; a verifier handed to `MarkDetector` wins"""
    proposer_model: str = ""
    """the proposer's ONNX file ("": the committed `proposer.onnx`), for judging a retrained one with the benches'
    `--set` (`python -m services.vision.proposer_training --out ...`; round vision43); a file that is no proposer is
    refused when the detector is made"""
    deflicker: bool = False
    """even out the bands a flickering light draws across a rolling-shutter frame before anything else
    (`deflicker.py`): where the rows' gain, estimated from the frame, is periodic (`deflicker_share` of its variance)
    and varies by `deflicker_depth` or more peak to peak, each row is divided by it. Round vision62 (stop 108)."""
    deflicker_share: float = DEFLICKER_SHARE
    deflicker_depth: float = DEFLICKER_DEPTH
    """with `deflicker`: the share of the rows' gain profile the bands must explain, and their least peak-to-peak gain
    (round vision62 chose 0.9 over 0.7 and 0.85 / 1.3 on tuning seed 7222: the fewest clean frames touched)"""
    danger_first: bool = True
    """judge the pyramid's levels coarsest first, verify each level's candidates as soon as it is done,
    and report the frame at the first X or TRIANGLE the verifier keeps: the finer levels and the proposer
    are not run on it. A frame with no danger mark gets the very detections it gets with this off (all
    levels, finest first, one verifier call, then the proposer). The reasoner lets danger win over an O
    in one observation, so what a danger frame no longer reports could not change a decision; an O held
    up beside an X is not counted towards its confirmation until the X is gone (the safe direction).
    On since round vision25c, with `text_whole` "turned" (the vision README): on fresh held-out seeds
    1.6 x the frames per CPU-second, 4 fewer missed X and triangles and 5 fewer missed O in 4,000 frames,
    2 more frames with a false mark; the stack's X shown -> stop write p50 77 -> 34 ms, p99 113 -> 68 ms
    on a slow two-core machine. Alone (round vision25) it saved the demo scene's X card little: the
    turned text-line test refused that X at every coarser level."""
    verify: bool = True
    """last check: the learned patch classifier (verifier.py) must agree. The card limits above
    (band paper, surround ink, margin texture, frame ink) were loosened when it came in (from 0.75,
    0.03, 0.25, 0.4), chosen on the tuning generator: without the verifier they let more false marks
    through. The contrast limits stay: a faint cross is a shadow or a crease, not print."""

    def __post_init__(self) -> None:
        """Settings no detector could run with are refused here, wherever they come from (code, the
        service's `--detector`, the benches' `--set`), so a service refuses them at start."""
        for f, block, *_ in self.levels:
            if f < 1 or block % 2 == 0 or block < 3:
                raise ValueError(f"bad pyramid level ({f}, {block}): factor >= 1, window odd and >= 3")
        if self.text_whole not in ("", "turned", "all"):
            raise ValueError(f"text_whole: {self.text_whole!r}: '' (off), 'turned' or 'all'")
        if not 0.0 <= self.text_twin < 1.0:
            raise ValueError(f"text_twin: {self.text_twin}: a share of the candidate's size, 0 (off) to below 1")
        unknown = set(self.card_rescue_from) - set(CARD_TESTS)
        if unknown:
            raise ValueError(f"card_rescue_from: unknown card tests {sorted(unknown)}; known: {CARD_TESTS}")
        if set(self.split.split(",")) - {"", "grey", "loose", "edge"}:
            raise ValueError(f"split: {self.split!r}: '' (off) or any of grey, loose, edge, comma-separated")
        for name in ("propose_thresholds", "propose_sure", "propose_sure_thresholds"):
            if len(getattr(self, name)) != 3:
                raise ValueError(f"{name}: {getattr(self, name)}: three, for X, O and TRIANGLE")
        if not all(0.0 <= v <= 1.0 for v in self.propose_sure):
            raise ValueError(f"propose_sure: {self.propose_sure}: heatmap peaks, 0 (never) to 1")
        for name in ("propose_thresholds", "propose_sure_thresholds"):
            if not all(v >= 0.0 for v in getattr(self, name)):
                raise ValueError(f"{name}: {getattr(self, name)}: the verifier's probabilities, 0 or more (above 1: "
                                 f"never kept)")
        if not 0.0 <= self.danger_contrast_ratio < 1.0:
            raise ValueError(f"danger_contrast_ratio: {self.danger_contrast_ratio}: a share of the paper's grey under 1 "
                             "(0: max_contrast_ratio)")
        windows = (self.texture_window, self.danger_texture_window, self.safe_texture_window)
        if not all(0.0 <= w <= 4.0 for w in windows):
            raise ValueError(f"texture_window {self.texture_window}, danger_texture_window {self.danger_texture_window}, "
                             f"safe_texture_window {self.safe_texture_window}: shares of the mark's extent, 0 (off) to 4")
        if not 0.0 <= self.filled_paper_round <= 1.0:
            raise ValueError(f"filled_paper_round: {self.filled_paper_round}: a share of the ring, 0 (off) to 1")
        if not 0.0 <= self.loose_confidence <= 1.0:
            raise ValueError(f"loose_confidence: {self.loose_confidence}: a verifier probability, 0 (off) to 1")
        if not 0.0 <= self.propose_o_clear <= 1.0 or not 0.0 < self.propose_o_middle <= 1.0:
            raise ValueError(f"propose_o_clear {self.propose_o_clear}, propose_o_middle {self.propose_o_middle}: "
                             "a share of the middle, 0 (off) to 1, and a share of the box, above 0 to 1")
        if not 0.0 <= self.o_clear <= 1.0 or not 0.0 <= self.o_clear_sure <= 1.0:
            raise ValueError(f"o_clear {self.o_clear}, o_clear_sure {self.o_clear_sure}: a share of the middle, 0 (off) "
                             "to 1, and a confidence, 0 to 1")
        if not 0.0 <= self.propose_open_margin <= 2.0:
            raise ValueError(f"propose_open_margin {self.propose_open_margin}: a share of the box's size, 0 to 2")
        if self.safe_card_extent < 0:
            raise ValueError(f"safe_card_extent {self.safe_card_extent}: pixels, 0 (any size) or more")
        if not -255.0 <= self.faint_veto_contrast <= 255.0:
            raise ValueError(f"faint_veto_contrast {self.faint_veto_contrast}: grey levels, -255 (every one) to 255")
        if not 0.0 <= self.safe_card_sure <= 1.0:
            raise ValueError(f"safe_card_sure {self.safe_card_sure}: a verifier probability, 0 (off) to 1")
        if not 0.0 <= self.safe_card_ink <= 1.0:
            raise ValueError(f"safe_card_ink {self.safe_card_ink}: a share of the card's part of the margin, 0 to 1")
        if not 0.0 <= self.o_islands <= 1.0:
            raise ValueError(f"o_islands {self.o_islands}: a share of the box, 0 (off) to 1")
        if not (0.0 <= self.star_depth <= 1.0 and self.star_spread > 0 and 0.0 <= self.star_inner <= 1.0):
            raise ValueError(f"star_depth {self.star_depth}, star_inner {self.star_inner}: shares, 0 to 1; star_spread "
                             f"{self.star_spread}: over 0")
        if not (0.0 <= self.open_side <= 1.0 and 0.0 <= self.propose_open_side <= 1.0 and 0.0 <= self.open_side_shade
                <= 1.0):
            raise ValueError(f"open_side {self.open_side}, propose_open_side {self.propose_open_side}, open_side_shade "
                             f"{self.open_side_shade}: shares of the side, 0 (off) to 1, and a shade from the paper (0) "
                             "to the ink (1)")
        if not 0.0 <= self.propose_t_fill <= 1.0 or self.propose_t_round < 0:
            raise ValueError(f"propose_t_fill {self.propose_t_fill}, propose_t_round {self.propose_t_round}: a share of "
                             "the enclosing triangle, 0 (off) to 1, and an ellipse residual, 0 or more")
        if self.propose_x_span < 0 or self.propose_x_ring <= 0 or self.propose_x_exits < 1:
            raise ValueError(f"propose_x_span {self.propose_x_span}, propose_x_ring {self.propose_x_ring}, "
                             f"propose_x_exits {self.propose_x_exits}: 0 (off) or more, above 0, 1 or more")
        if not 0.0 < self.propose_x_arc <= 1.0 or not 0.0 <= self.propose_x_cover <= 1.0:
            raise ValueError(f"propose_x_arc {self.propose_x_arc}, propose_x_cover {self.propose_x_cover}: shares of "
                             "the circle, above 0 to 1, and 0 (off) to 1")
        for name in ("hand_triangle", "hand_triangle_loose", "hand_triangle_floor", "hand_triangle_solid"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name}: {getattr(self, name)}: a probability, 0 (off) to 1")
        for name, maker in (
            ("hand_triangle_model", "training"), ("proposer_model", "proposer_training"), ("verifier_model", "ensemble")
        ):
            path = getattr(self, name)
            if path and not Path(path).is_file():
                raise ValueError(
                    f"{name}: {path!r}: no such file (give an ONNX file made by python -m services.vision.{maker}, "
                    "or '' for the committed one)"
                )


@dataclass
class Candidate:
    """A component that passed the shape tests, or a loose one (for training the verifier): its claimed
    shape, box in input pixels, the verifier's image input (`verifier.crops`) and whether the whole
    detector (before the verifier) kept it (never, for a loose one: without the verifier nothing names
    it)."""

    shape: Shape | None  # None: a loose candidate (the shape tests found none, the verifier names it)
    box: Box
    crops: np.ndarray  # (3, 32, 32) uint8: tight, wide and context crops
    kept: bool = False


CARD_TESTS: tuple[str, ...] = ("band", "faint", "letter", "beside", "ratio", "texture", "ink")
"""The card tests `_on_card` can refuse a mark for (its docstring says what each checks)."""

STAGES: tuple[str, ...] = (
    "no component",  # no binarised component overlaps the mark
    "size/fill",  # the vectorised pre-filter: size, aspect, fill ratio, frame edge
    "frame ink",  # too much ink in the thin frame around its box
    "shape",  # the contour shape tests found no mark, or another shape
    "unnamed",  # a loose candidate (the shape tests claimed nothing) the verifier did not name at its stricter bar
    "card",  # the card tests (band, contrast, card texture, other ink, a letter beside it)
    "O margin",  # the O's wide clear margin
    "hole",  # a ring's or triangle's hole is not paper
    "confidence",  # below `min_confidence` (`loose_confidence` for a loose candidate the verifier named)
    "text line",  # a letter inside a line of text
    "verifier",  # the learned verifier disagreed
    "kept",
)
"""Where a component's journey through the detector ends, in order (`MarkDetector.trace`)."""


@dataclass(frozen=True)
class Traced:
    """One component at one pyramid level: its box in input pixels, the shape the shape tests claimed
    (None before them or when they found none) and the last stage it reached (`STAGES`)."""

    box: Box
    shape: Shape | None
    stage: str
    scale: int = 1  # the pyramid level's downscale factor


@dataclass(frozen=True)
class Detection:
    shape: Shape
    confidence: float
    box: Box  # x, y, w, h in pixels of the input image

    def to_mark(self) -> Mark:
        return Mark(shape=self.shape, confidence=round(self.confidence, 4), box=self.box)


@dataclass(frozen=True)
class _Blob:
    """One component at one scale, with its contours relative to the ROI origin."""

    outer: np.ndarray
    holes: list[np.ndarray]
    area: float  # area enclosed by the outer contour
    size: float  # max(w, h) at this scale


@dataclass(frozen=True)
class _Level:
    """One pyramid level of a frame: its grey image, binarisation, components and downscale factor."""

    g: np.ndarray
    binary: np.ndarray
    labels: np.ndarray
    stats: np.ndarray
    f: int
    text_check: bool


@dataclass
class _Pending:
    """A candidate waiting for the frame's one verifier call: `shape` is what the shape tests claimed
    (then `det` passed every other test) or None for a loose one (then `blob` and `own` are kept for the
    context tests once the verifier has named it). `box` is in the level's pixels."""

    level: _Level
    i: int
    box: Box
    shape: Shape | None
    det: Detection | None = None
    blob: _Blob | None = None
    own: np.ndarray | None = None
    trace_at: int | None = None  # its entry in the trace, updated with the verifier's verdict
    rescue: bool = False  # a danger mark the card tests refused: kept only if the network is very sure
    part: bool = False  # a loose part `_split` cut off a bigger component: never named O
    spared: bool = False  # an O its card spared at the clear margin: it needs `safe_card_sure`


def changed_settings(config: DetectorConfig) -> str:
    """The settings of `config` that differ from the defaults, as `parse_settings` reads them ("" for none)."""
    defaults = DetectorConfig()
    out = []
    for f in fields(DetectorConfig):
        value = getattr(config, f.name)
        if value != getattr(defaults, f.name):
            if f.name == "levels":
                text = ",".join(":".join(str(v) for v in level) for level in value)
            elif isinstance(value, tuple):
                text = ",".join(str(v) for v in value)
            else:
                text = str(value)
            out.append(f"{f.name}={text}")
    return " ".join(out)


def parse_levels(text: str) -> tuple[tuple[int, ...], ...]:
    """A pyramid written as text (`levels=...`'s value): "1:31,2:31:50,4:31" -> ((1, 31), (2, 31, 50), (4, 31)).
    ValueError if a level is not two or three whole numbers."""
    levels = tuple(tuple(int(v) for v in level.split(":")) for level in text.split(",") if level)
    if not levels or any(len(level) not in (2, 3) for level in levels):
        raise ValueError(text)
    return levels


def parse_settings(items: str | Iterable[str]) -> DetectorConfig:
    """The default `DetectorConfig` with some settings changed: `KEY=VALUE` items (a string is split at
    spaces and semicolons: `--detector` / `HRI_VISION_DETECTOR`, e.g. "split= card_rescue=0.97"; the
    benches' `--set`). Booleans are 1/0, true/false, yes/no or on/off; a tuple's items are comma-separated
    (`card_rescue_from=band,texture`); `split=` is the empty string (off); `levels` is the pyramid, its
    levels comma-separated and each level's numbers colon-separated (`levels=1:31,2:31:50,4:31`, the
    pyramid before round vision16). ValueError names the item that is no setting or whose value is not
    of the setting's type."""
    from services.runtime.flags import parse_flag  # here: the detector itself needs no bus runtime

    if isinstance(items, str):
        items = [t for t in re.split(r"[;\s]+", items) if t]
    defaults = DetectorConfig()
    names = {f.name for f in fields(DetectorConfig)}
    changed: dict[str, object] = {}
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or key not in names:
            raise ValueError(
                f"detector setting {item!r}: expected KEY=VALUE, KEY one of {', '.join(sorted(names))}"
            )
        old = getattr(defaults, key)
        try:
            if key == "levels":
                changed[key] = parse_levels(value)
            elif isinstance(old, bool):
                flag = parse_flag(value)
                if flag is None:
                    raise ValueError(value)
                changed[key] = flag
            elif isinstance(old, tuple):
                kind = type(old[0]) if old else str
                changed[key] = tuple(kind(v) for v in value.split(",") if v)
            else:
                changed[key] = type(old)(value)
        except ValueError:
            kind = "pyramid (FACTOR:WINDOW[:LARGEST],...)" if key == "levels" else type(old).__name__
            raise ValueError(f"detector setting {item!r}: {value!r} is not a {kind}") from None
    return replace(defaults, **changed)  # type: ignore[arg-type]  # DetectorConfig checks the values


class MarkDetector:
    """Stateless per frame; safe to reuse for every frame of a stream (not across threads)."""

    def __init__(self, config: DetectorConfig | None = None, verifier: Verifier | None = None) -> None:
        self.config = config or DetectorConfig()
        if verifier is None and self.config.verify:
            verifier = Verifier.load(Path(self.config.verifier_model) if self.config.verifier_model else MODEL_PATH)
        self.verifier = verifier if self.config.verify else None
        proposer = Path(self.config.proposer_model) if self.config.proposer_model else PROPOSER_PATH
        self.proposer = Proposer.load(proposer) if self.config.propose > 0 and self.verifier is not None else None
        asked = max(self.config.hand_triangle, self.config.hand_triangle_loose) > 0 and self.verifier is not None
        model = Path(self.config.hand_triangle_model) if self.config.hand_triangle_model else TRIANGLES_PATH
        self.triangles = Verifier.load(model) if asked else None
        """the second network `hand_triangle` (and `hand_triangle_loose`) asks, or None"""
        self._seen: list[Candidate] | None = None  # collecting candidates (training), or None
        self._trace: list[Traced] | None = None  # recording every component's last stage, or None
        self._claimed: Shape | None = None  # the shape the last judged component was taken for
        self._why = ""  # the stage at which `_judge` last rejected a component
        self._card_refusal = ""  # and, at the card stage, which test (`_on_card`)
        self._spared = False  # whether the last O `_finish` kept passed its clear margin only on its card
        self._f = 1
        self._max_size = 0  # the largest component judged at the current level (0: any)
        self._greys: dict[int, np.ndarray] = {}  # this frame's grey image at each pyramid level
        self._gray: np.ndarray | None = None  # this frame's grey image at full working resolution (`star`)
        self._levels: list[_Level] = []  # this frame's pyramid levels, for the proposals' text test
        self._vetoes: list[Box] = []
        """this frame's components the context tests refused, in input pixels: no proposal over them is
        kept (the card tests judged them; only the verifier's rescue may overrule them)"""

    def candidates(self, image: np.ndarray) -> list[Candidate]:
        """Every component that passes the shape tests, with its crops and the detector's verdict
        (before the verifier): the verifier's training data. `image` must be at most `max_side`."""
        gray = to_gray(image)
        if max(gray.shape) > self.config.max_side:
            raise ValueError(f"candidates() wants frames of at most {self.config.max_side} px")
        self._seen = []
        verifier, self.verifier = self.verifier, None
        try:
            finish(self._detect_gray(gray))
            return self._seen
        finally:
            self._seen, self.verifier = None, verifier

    def trace(self, image: np.ndarray) -> tuple[list[Detection], list[Traced]]:
        """`detect` plus the last stage every sizeable component reached (for `bench/vision_stages.py`:
        where true marks are lost). `image` must be at most `max_side`; slower than `detect`."""
        gray = to_gray(image)
        if max(gray.shape) > self.config.max_side:
            raise ValueError(f"trace() wants frames of at most {self.config.max_side} px")
        self._trace = []
        try:
            found = finish(self._detect_gray(gray))
            return found, self._trace
        finally:
            self._trace = None

    def detect(self, image: np.ndarray) -> list[Detection]:
        return finish(self.steps(image))

    def steps(self, image: np.ndarray) -> Steps:
        """`detect` in steps, for a caller that wants to do something else between them (the vision
        service looks at a newer frame's coarser levels: `lookahead.py`): the very same work and
        detections. Another frame's steps may run meanwhile only on another instance (`twin`)."""
        gray, scale = working_gray(image, self.config.max_side)
        found = yield from self._detect_gray(gray)
        if scale == 1.0:
            return found
        return [
            Detection(d.shape, d.confidence, tuple(round(v * scale) for v in d.box))  # type: ignore[arg-type]
            for d in found
        ]

    def twin(self) -> MarkDetector:
        """A second detector with the same settings and the same loaded networks (no more memory for
        them), for a second frame in flight: a frame's working state lives on its detector."""
        other = copy.copy(self)
        other._greys, other._levels, other._vetoes, other._gray = {}, [], [], None
        return other

    def _detect_gray(self, gray: np.ndarray) -> Steps:
        """Every pyramid level, then one batched verifier call for all of their candidates, then the
        proposer; or, with `danger_first`, level by level from the coarsest, stopping at a danger mark
        (then `Step.FINE` before the finest level: none was found in the others)."""
        if self.config.deflicker:
            gray = deflicker(gray, self.config.deflicker_share, self.config.deflicker_depth)
        found: list[Detection] = []
        pending: list[_Pending] = []
        self._greys, self._vetoes, self._levels, self._gray = {}, [], [], gray
        levels = self.config.levels
        early = self.config.danger_first and self.verifier is not None
        if early:
            levels = tuple(sorted(levels, key=lambda level: -level[0]))
        finest = min(f for f, *_ in levels)
        for f, block, *cap in levels:
            yield Step.FINE if early and f == finest and len(levels) > 1 else Step.TICK
            if f == 1:
                g = cv2.GaussianBlur(gray, (3, 3), 0)
            else:
                w, h = gray.shape[1] // f, gray.shape[0] // f
                if min(w, h) < 2 * self.config.min_size:
                    continue
                g = cv2.resize(gray, (w, h), interpolation=cv2.INTER_AREA)
            self._f = f
            self._greys[f] = g
            self._max_size = cap[0] if cap else 0
            if f == 1 and len(self.config.levels) > 1 and self.config.full_res_max:
                self._max_size = self.config.full_res_max
            found += yield from self._detect_scale(
                g, block, text_check=f <= self.config.text_max_f, pending=pending
            )
            if early and pending:
                yield Step.TICK
                found += self._verify(pending)
                pending = []
                if any(d.shape is not Shape.O for d in found):
                    return self._blank_middles(gray, _merge(found, self.config.overlap))
        if pending:
            yield Step.TICK
            found += self._verify(pending)
        if self.proposer is not None and self.verifier is not None:
            yield Step.TICK
            found += self._proposed(gray, found)
        return self._blank_middles(gray, _merge(found, self.config.overlap))

    def _proposed(self, gray: np.ndarray, found: list[Detection]) -> list[Detection]:
        """The proposer's peaks where nothing was detected (`_judged_proposals`), each kept if the verifier gives
        the proposed shape enough probability (`DetectorConfig.propose_thresholds`; with a peak of its shape's
        `propose_sure` or more, `propose_sure_thresholds` where they are lower)."""
        cfg = self.config
        out = []
        for p, row in self._judged_proposals(gray, found):
            k = CLASSES.index(p.shape)
            need = cfg.propose_thresholds[k]
            if 0 < cfg.propose_sure[k] <= p.score:
                need = min(need, cfg.propose_sure_thresholds[k])
            if row[k] < need or (p.shape is Shape.X and self._runs_on(p.box)):
                continue
            sure_only = row[k] < cfg.propose_thresholds[k]  # kept only because the proposer is sure
            if p.shape is Shape.O and sure_only and cfg.propose_o_clear:
                if self.middle_ink(gray, p.box) > cfg.propose_o_clear:
                    continue
            if p.shape is Shape.TRIANGLE and cfg.propose_t_fill and self.cornerless(gray, p.box):
                continue
            if p.shape is Shape.TRIANGLE and cfg.propose_open_side and self.open_proposal(gray, p.box):
                continue
            if p.shape is not Shape.O and self.star(p.box):
                continue
            out.append(Detection(p.shape, float(row[k]), p.box))
        return out

    def middle_ink(self, gray: np.ndarray, box: Box) -> float:
        """`middle_ink` of a proposal's `box` (frame pixels) in the frame just detected, at the pyramid level the
        verifier's crops were cut from (`proposal_crops`)."""
        f = self._crop_level(box)
        return middle_ink(self._greys.get(f, gray), _down(box, f), self.config.propose_o_middle)

    def _blank_middles(self, gray: np.ndarray, found: list[Detection]) -> list[Detection]:
        """`found` without the O whose middle is not blank: an unsure one with ink there (`DetectorConfig.o_clear`,
        `o_clear_sure`), any with islands of ink in its hole (`o_islands`)."""
        cfg = self.config
        return [
            d
            for d in found
            if d.shape is not Shape.O
            or (
                (not cfg.o_clear or d.confidence >= cfg.o_clear_sure
                 or middle_ink(gray, d.box, cfg.propose_o_middle) <= cfg.o_clear)
                and (not cfg.o_islands or hole_islands(gray, d.box) <= cfg.o_islands)
            )
        ]

    def cornerless(self, gray: np.ndarray, box: Box) -> bool:
        """Whether the ink at the middle of a proposal's `box` (frame pixels) is one solid round blob, no triangle
        (`middle_blob`, `DetectorConfig.propose_t_fill` and `propose_t_round`)."""
        b = middle_blob(gray, box)
        cfg = self.config
        return b is not None and b.triangle_fill < cfg.propose_t_fill and b.roundness <= cfg.propose_t_round

    def open_proposal(self, gray: np.ndarray, box: Box) -> bool:
        """Whether the largest blob of ink in a proposal's `box` (frame pixels) is two strokes meeting at an angle, not
        a triangle: no hole, one side open and as light as the paper (`box_outline`, `open_side`,
        `DetectorConfig.propose_open_side`)."""
        outline = box_outline(gray, box, self.config.propose_open_margin)
        return outline is not None and self._two_strokes(gray, outline, self.config.propose_open_side)

    def star(self, box: Box) -> bool:
        """Whether the largest blob of ink in `box` (frame pixels) of the frame being detected is a star: five or more
        deep notches spread evenly round it (`notches`, `DetectorConfig.star_depth`)."""
        cfg = self.config
        if not cfg.star_depth or self._gray is None:
            return False
        n = notches(self._gray, box, cfg.star_depth)
        return n is not None and n.star(cfg.star_spread, cfg.star_inner)

    def _two_strokes(self, g: np.ndarray, outline: np.ndarray, bar: float) -> bool:
        """Whether `outline` (in `g`'s pixels) leaves one side of its enclosing triangle open, drawn along less than
        `bar` of it, and as light as the paper there (`open_side`, `DetectorConfig.open_side_shade`)."""
        side = open_side(g, outline)
        return side is not None and side.cover < bar and side.shade < self.config.open_side_shade

    def _runs_on(self, box: Box) -> bool:
        """Whether the ink at the middle of `box` (frame pixels) runs on past it as crossing strokes do
        (`DetectorConfig.propose_x_span`; 0: never)."""
        cfg = self.config
        if not cfg.propose_x_span or not self._levels:
            return False
        level = min(self._levels, key=lambda lv: lv.f)
        x, y, w, h = _down(box, level.f)
        mx, my = 3 * w // 10, 3 * h // 10  # the middle 40 %: where an X's strokes cross
        middle = level.labels[max(0, y + my) : max(0, y + h - my), max(0, x + mx) : max(0, x + w - mx)]
        ids = np.unique(middle[middle > 0])
        ids = ids[np.maximum(level.stats[ids, 2], level.stats[ids, 3]) >= cfg.propose_x_span * max(w, h)]
        if not len(ids):
            return False
        r = cfg.propose_x_ring * max(w, h)
        n = max(64, int(2 * np.pi * r))  # a sample a pixel: a thin stroke is not stepped over
        t = np.arange(n) * 2 * np.pi / n
        px = np.round(x + w / 2 + r * np.cos(t)).astype(int)
        py = np.round(y + h / 2 + r * np.sin(t)).astype(int)
        rows, cols = level.labels.shape
        inside = (px >= 0) & (py >= 0) & (px < cols) & (py < rows)
        on = np.zeros(n, bool)
        on[inside] = np.isin(level.labels[py[inside], px[inside]], ids)
        if on.all() or not on.any():
            return False
        start = int(np.argmin(on))  # walk the circle from a point off the ink: every run is whole
        edges = np.diff(np.concatenate(([0], np.roll(on, -start).astype(np.int8), [0])))
        runs = np.flatnonzero(edges < 0) - np.flatnonzero(edges > 0)
        if cfg.propose_x_cover and (runs.sum() > cfg.propose_x_cover * n or len(runs) > 2 * cfg.propose_x_exits):
            return False
        return bool(len(runs) >= cfg.propose_x_exits and runs.max() <= cfg.propose_x_arc * n)

    def _judged_proposals(self, gray: np.ndarray, found: list[Detection]) -> list[tuple[Proposal, np.ndarray]]:
        """The proposer's peaks (`propose`) where nothing was detected, each with the verifier's probabilities
        for its box shown as a loose candidate (cropped at the coarsest level where it is still 48 px), in one
        call. Never over a component the context tests refused (the card tests, the O's margin, a line of text:
        only the verifier's rescue may overrule some of them), nor over any letter in a line of text
        (`_in_text`)."""
        assert self.proposer is not None and self.verifier is not None
        props = [
            p
            for p in self.proposer.propose(gray, self.config.propose)
            if all(box_overlap(p.box, d.box) <= 0.3 for d in found)
            and not any(box_overlap(p.box, box) > 0.5 for box in self._vetoes)
            and not self._in_text(p.box)
        ]
        if not props:
            return []
        patches = np.stack([self.proposal_crops(gray, p.box) for p in props])
        probs = self.verifier.probabilities(patches, np.stack([claim(None)] * len(props)))
        return list(zip(props, probs, strict=True))

    def proposal_crops(self, gray: np.ndarray, box: Box) -> np.ndarray:
        """The verifier's crops of a proposal's `box` in the frame just detected (or harvested), cut at
        the coarsest pyramid level where the box is still 48 px (`gray`: the frame, if none is)."""
        f = self._crop_level(box)
        return crops(self._greys.get(f, gray), _down(box, f))

    def _crop_level(self, box: Box) -> int:
        """The coarsest pyramid level of the frame just detected where `box` (frame pixels) is still 48 px."""
        return max((f for f in self._greys if max(box[2:]) / f >= 48), default=min(self._greys, default=1))

    def _in_text(self, box: Box) -> bool:
        """Whether a component of about `box`'s size over it, at any pyramid level the text-line test
        runs on, is a letter in a line of text."""
        for level in self._levels:
            if not level.text_check:
                continue
            x, y, w, h = _down(box, level.f)
            st = level.stats
            ix = np.minimum(st[:, 0] + st[:, 2], x + w) - np.maximum(st[:, 0], x)
            iy = np.minimum(st[:, 1] + st[:, 3], y + h) - np.maximum(st[:, 1], y)
            inter = np.clip(ix, 0, None) * np.clip(iy, 0, None)
            size = np.maximum(st[:, 2], st[:, 3])
            over = (inter >= 0.5 * np.minimum(st[:, 2] * st[:, 3], w * h)) & (size >= 0.5 * max(w, h))
            over &= size <= 2 * max(w, h)
            over[0] = False
            if any(self._text_line(level, int(i)) for i in np.flatnonzero(over)):
                return True
        return False

    def _verify(self, pending: list[_Pending]) -> list[Detection]:
        """The learned verifier on every candidate of the frame in one call: a claimed one stays if it
        agrees; a loose one gets the shape it names, then the card tests judge it like any other."""
        assert self.verifier is not None
        patches = np.stack([self._crops(p) for p in pending])
        claims = np.stack([claim(p.shape) for p in pending])
        probs = self.verifier.probabilities(patches, claims)
        second = self._second_triangles(pending, patches, claims, probs)
        out: list[Detection] = []
        for p, row, kept in zip(pending, probs, second, strict=True):
            det: Detection | None = None
            if p.rescue:
                assert p.shape is not None
                claimed, stage = p.shape, "card"
                if row[CLASSES.index(p.shape)] >= self.config.card_rescue:
                    det, stage = p.det, "kept"
            elif p.shape is not None:
                claimed, stage = p.shape, "verifier"
                if self._unsure_of_spared(p, p.spared, float(row[CLASSES.index(Shape.O)])):
                    stage = "O margin"
                elif self.verifier.accepts(row, p.shape) or kept is not None:
                    det, stage = p.det, "kept"
                elif p.shape is Shape.TRIANGLE and self._filled_on_paper(p) is not None:
                    det, stage = p.det, "kept"
            else:
                claimed, prob, ok = self.verifier.name(row)
                stage = "unnamed"
                if kept is not None:  # named by the second network alone: the card tests must pass
                    claimed, prob = Shape.TRIANGLE, kept
                    assert p.blob is not None and p.own is not None
                    if self._open(p):
                        stage = "shape"
                    else:
                        det = self._finish(p.level, p.i, p.blob, p.own, claimed, prob, box=p.box, named=True)
                        stage = "kept" if det is not None else self._why
                    ok = False
                elif not ok and claimed is Shape.TRIANGLE and (fill := self._filled_on_paper(p)) is not None:
                    # a filled triangle with paper all round, which the networks took for one painted on a wall: the
                    # card tests judge it, its confidence the shape's fit (as the shape tests give a claimed one)
                    assert p.blob is not None and p.own is not None
                    conf = 1.0 - 0.5 * max(0.0, 1.0 - fill) / (1.0 - LOOSE_TRIANGLE_FILL)
                    det = self._finish(p.level, p.i, p.blob, p.own, claimed, conf, box=p.box)
                    stage = "kept" if det is not None else self._why
                if ok and claimed is Shape.TRIANGLE and self._open(p):
                    ok, stage = False, "shape"
                if ok and not (p.part and claimed is Shape.O):
                    assert p.blob is not None and p.own is not None
                    blob = p.blob
                    if p.part and claimed is Shape.X:  # a loop closed by a finger's edge: no hole
                        blob = _Blob(blob.outer, [], blob.area, blob.size)
                    det = self._finish(p.level, p.i, blob, p.own, claimed, prob, box=p.box, named=True)
                    stage = "kept" if det is not None else self._why
                    if det is not None and self._unsure_of_spared(p, self._spared, prob):
                        det, stage = None, "O margin"
                    if (
                        det is None
                        and self._rescuable(claimed, p.level, p.i)
                        and prob >= self.config.card_rescue
                    ):
                        det, stage = Detection(claimed, prob, p.box), "kept"
            if det is not None and det.shape is not Shape.O and self.star(_up(det.box, p.level.f)):
                det, stage = None, "shape"
            if self._trace is not None and p.trace_at is not None:
                t = self._trace[p.trace_at]
                self._trace[p.trace_at] = Traced(t.box, claimed, stage, t.scale)
            if det is not None:
                out.append(Detection(det.shape, det.confidence, _up(det.box, p.level.f)))
        return out

    def _filled_on_paper(self, p: _Pending) -> float | None:
        """For a claimed TRIANGLE, or a loose candidate, that is filled and has paper all round it
        (`DetectorConfig.filled_paper_round`): how well it fills its enclosing triangle (a loose one must fill
        `LOOSE_TRIANGLE_FILL` of it); else None."""
        share = self.config.filled_paper_round
        if share <= 0:
            return None
        x, y, w, h = p.box
        own = p.own if p.own is not None else cv2.inRange(p.level.labels[y : y + h, x : x + w], p.i, p.i)
        outlines = cv2.findContours(own, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0]
        if not outlines:
            return None
        outline = max(outlines, key=cv2.contourArea)
        fill = _triangle_fill(outline, cv2.contourArea(outline))
        if p.shape is None and fill < LOOSE_TRIANGLE_FILL:
            return None
        g = p.level.g
        ink, paper = ink_and_paper(g, p.box)
        if solid_share(g, p.box, outline, ink, paper) < FILLED_SHARE:
            return None
        return fill if paper_round(g, p.box, outline, ink, paper) >= share else None

    def _open(self, p: _Pending) -> bool:
        """Whether a loose candidate named a TRIANGLE is two strokes meeting at an angle, not a triangle: no hole, one
        side of its enclosing triangle open and as light as the paper round it (`DetectorConfig.open_side`)."""
        cfg = self.config
        if cfg.open_side <= 0 or p.blob is None or p.blob.holes:
            return False
        x, y = p.box[:2]
        return self._two_strokes(p.level.g, p.blob.outer + np.array([x - 1, y - 1], np.int32), cfg.open_side)

    def _second_triangles(
        self, pending: list[_Pending], patches: np.ndarray, claims: np.ndarray, probs: np.ndarray
    ) -> list[float | None]:
        """For each candidate, the second network's TRIANGLE probability if it keeps it, else None. It is asked
        only about a claimed TRIANGLE the verifier refused (`hand_triangle`; not one the card tests refused:
        `rescue`) and a loose candidate the verifier named nothing but half-believes a TRIANGLE
        (`hand_triangle_loose`, `hand_triangle_floor`): few, so it costs little."""
        out: list[float | None] = [None] * len(pending)
        if self.triangles is None:
            return out
        assert self.verifier is not None
        cfg = self.config
        k = CLASSES.index(Shape.TRIANGLE)
        need: dict[int, float] = {}
        for j, (p, row) in enumerate(zip(pending, probs, strict=True)):
            if p.rescue:
                continue
            if p.shape is Shape.TRIANGLE and cfg.hand_triangle > 0 and not self.verifier.accepts(row, p.shape):
                need[j] = cfg.hand_triangle
            elif (
                p.shape is None
                and cfg.hand_triangle_loose > 0
                and row[k] >= cfg.hand_triangle_floor
                and not self.verifier.name(row)[2]
                and not _solid(p.blob, cfg.hand_triangle_solid)
            ):
                need[j] = cfg.hand_triangle_loose
        if need:
            ask = list(need)
            for j, row in zip(ask, self.triangles.probabilities(patches[ask], claims[ask]), strict=True):
                if row[k] >= need[j]:
                    out[j] = float(row[k])
        return out

    def _crops(self, p: _Pending) -> np.ndarray:
        """The verifier's input for a candidate; a big part `_split` cut off at full resolution is cropped
        from the half-resolution level instead (a quarter of the pixels to resize, about the same
        32x32 crops: a big component at full resolution is otherwise left to the coarser levels)."""
        if p.part and p.level.f == 1 and max(p.box[2:]) > self.config.loose_max_size and 2 in self._greys:
            x, y, w, h = p.box
            return crops(self._greys[2], (x // 2, y // 2, max(1, w // 2), max(1, h // 2)))
        return crops(p.level.g, p.box)

    def _unsure_of_spared(self, p: _Pending, spared: bool, o_prob: float) -> bool:
        """Whether candidate `p`, an O its card `spared` at the clear margin, has a verifier O probability `o_prob`
        under `safe_card_sure`: then it is refused at its margin after all, and recorded as a veto like any O refused
        there (no proposal over it is kept either). The one place the rule lives, for a claimed and a named O."""
        if not spared or o_prob >= self.config.safe_card_sure:
            return False
        self._vetoes.append(_up(p.box, p.level.f))
        return True

    def _rescuable(self, shape: Shape, level: _Level, i: int) -> bool:
        """Whether component `i`, just refused by `_finish`, may still be kept on the verifier's word
        alone (`DetectorConfig.card_rescue`): a danger mark refused by one of the card tests in
        `card_rescue_from`, and not a letter in a line of text (a word is clutter whatever the network
        thinks of one of its letters)."""
        return (
            self._rescues(shape)
            and self._why == "card"
            and self._card_refusal in self.config.card_rescue_from
            and not self._text_line(level, i)
        )

    def _rescues(self, shape: Shape) -> bool:
        """Whether the rescue is on and may keep a mark of `shape`: a danger mark, never an O."""
        return self.config.card_rescue > 0 and shape in (Shape.X, Shape.TRIANGLE)

    def _text_line(self, level: _Level, i: int) -> bool:
        """Component `i` is a letter in a line of text (on the levels the test runs on: `text_max_f`)."""
        return level.text_check and _in_text_line(
            level.stats,
            i,
            level.g,
            level.labels,
            self.config.text_paper,
            self.config.text_turned,
            self.config.text_whole,
            self.config.text_twin,
        )

    # ------------------------------------------------------------------ one pyramid level
    def _detect_scale(
        self, g: np.ndarray, block: int, text_check: bool, pending: list[_Pending]
    ) -> Generator[Step, None, list[Detection]]:
        """The detections of one level the verifier need not see (it is off), in this level's pixels
        scaled to the input's; the candidates it must judge are added to `pending`."""
        cfg = self.config
        binary = cv2.adaptiveThreshold(
            g, 255, cv2.ADAPTIVE_THRESH_MEAN_C, cv2.THRESH_BINARY_INV, block, cfg.offset
        )
        n, labels, stats = _components(binary)
        if n <= 1:
            return []
        H, W = g.shape
        x, y, w, h, area = (stats[:, i] for i in range(5))
        fill = area / np.maximum(w * h, 1)
        long_side, short_side = np.maximum(w, h), np.minimum(w, h)
        fits = (  # the size, aspect and fill of a mark
            (short_side >= cfg.min_size)
            & (long_side <= 0.98 * min(H, W))
            & (long_side <= cfg.max_aspect * short_side)
            & (fill >= 0.08)
            & (fill <= 0.62)  # a filled disc is 0.79, a filled square 1
        )
        if self._max_size:
            fits &= long_side <= self._max_size
        fits[0] = False  # background label
        in_frame = (x > 0) & (y > 0) & (x + w < W) & (y + h < H)
        keep = fits & in_frame  # cut by the frame edge: not judged
        candidates = np.flatnonzero(keep)
        if len(candidates):
            candidates = candidates[
                _clear_frames(binary, stats[candidates], cfg.frame_margin, cfg.frame_max_ink)
            ]
        # ... except a mark joined to a finger that runs on out of the frame (a hand holding the card):
        # that component is only ever split (`DetectorConfig.split`, "edge")
        cut = fits & ~in_frame & (long_side >= cfg.split_min) if self._splits_edge() else np.zeros_like(keep)
        judged_here = np.r_[candidates, np.flatnonzero(cut)]
        trace = self._trace
        if trace is not None:
            self._trace_prefilter(stats, keep | cut, judged_here, min(H, W))
        level = _Level(g, binary, labels, stats, self._f, text_check)
        self._levels.append(level)
        out: list[Detection] = []
        for i in judged_here.tolist():
            yield Step.TICK
            judged = self._judge(level, i, at_edge=bool(cut[i]))
            stage = self._why
            wait: _Pending | None = None
            det: Detection | None = None
            if isinstance(judged, _Pending):
                wait, stage = judged, "verifier"
            elif judged is not None:
                if self._seen:
                    self._seen[-1].kept = True
                if self.verifier is not None:
                    spared = judged.shape is Shape.O and self._spared
                    wait = _Pending(level, int(i), judged.box, judged.shape, det=judged, spared=spared)
                    stage = "verifier"
                else:
                    det, stage = judged, "kept"
            if trace is not None:
                claimed = judged.shape if judged is not None else self._claimed
                at = judged.box if judged is not None else stats[i]  # a part `_split` cut off
                trace.append(Traced(_up(at, self._f), claimed, stage, self._f))
            if wait is not None:
                wait.trace_at = len(trace) - 1 if trace is not None else None
                pending.append(wait)
            if det is not None:
                out.append(Detection(det.shape, det.confidence, _up(det.box, self._f)))
        return out

    def _trace_prefilter(self, stats: np.ndarray, keep: np.ndarray, passed: np.ndarray, side: int) -> None:
        """Record the components the vectorised pre-filters dropped (only those big enough to be a
        mark at all: the rest is speckle)."""
        assert self._trace is not None
        f = self._f
        big = (np.maximum(stats[:, 2], stats[:, 3]) >= self.config.min_size // 2) & (
            np.maximum(stats[:, 2], stats[:, 3]) <= side
        )
        big[0] = False
        frame_dropped = keep.copy()
        frame_dropped[passed] = False
        for i in np.flatnonzero(big & ~keep):
            self._trace.append(Traced(_up(stats[i], f), None, "size/fill", f))
        for i in np.flatnonzero(frame_dropped):
            self._trace.append(Traced(_up(stats[i], f), None, "frame ink", f))

    def _splits_edge(self) -> bool:
        """Whether components cut by the frame edge are split at this level (never while harvesting)."""
        cfg = self.config
        return "edge" in cfg.split.split(",") and self._f in cfg.split_levels and self._seen is None

    def _judge(self, level: _Level, i: int, at_edge: bool = False) -> Detection | _Pending | None:
        """Component `i`: a detection in the level's pixels if the shape tests read a mark and every
        context test passes (the verifier still to come); a pending loose candidate for the verifier
        to name; or None (`_why` says where it stopped). A component cut by the frame edge
        (`at_edge`) is never judged whole: only the parts `_split` cuts from it."""
        x, y, w, h = level.stats[i, :4].tolist()
        size = float(max(w, h))
        self._why, self._claimed = "shape", None
        # the shape first, on the component's own box (cheap: most candidates end here), with a pixel
        # of background all round for findContours: the labels around the box, where none is i
        H, W = level.labels.shape
        if x > 0 and y > 0 and x + w < W and y + h < H:  # always, after the pre-filter
            bordered = cv2.inRange(level.labels[y - 1 : y + h + 1, x - 1 : x + w + 1], i, i)
        else:
            mask = cv2.inRange(level.labels[y : y + h, x : x + w], i, i)
            bordered = cv2.copyMakeBorder(mask, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
        own = bordered[1:-1, 1:-1]  # 255 where the label is i
        if at_edge:
            parts = self._split(level, i, own, (x, y, w, h))
            if parts is None:
                self._why, self._claimed = "shape", None
            return parts
        blob = _blob(bordered, size)
        if blob is None:
            return None
        judged = _classify(blob, self.config)
        if judged is None:
            whole = self._loose(level.g, own, blob, (x, y, w, h))
            parts = self._split(level, i, own, (x, y, w, h), loose_part=not whole)
            if parts is not None:
                return parts
            self._why, self._claimed = "shape", None
            if whole:
                return _Pending(level, i, (x, y, w, h), None, blob=blob, own=own)
            return None
        shape, conf = judged
        if self._seen is not None:
            self._seen.append(Candidate(shape, _up((x, y, w, h), self._f), crops(level.g, (x, y, w, h))))
        det = self._finish(level, i, blob, own, shape, conf)
        if det is None and self.verifier is not None and self._rescuable(shape, level, i):
            box = (x, y, w, h)
            return _Pending(level, i, box, shape, det=Detection(shape, conf, box), rescue=True)
        return det

    def _finish(
        self,
        level: _Level,
        i: int,
        blob: _Blob,
        own: np.ndarray,
        shape: Shape,
        conf: float,
        box: Box | None = None,
        named: bool = False,
    ) -> Detection | None:
        """The context tests of a component taken for `shape` (by the shape tests or, for a loose one,
        the verifier: `named`, its confidence the verifier's probability): the card, the O's margin, the hole,
        the confidence and a line of text. `box` and `own` are a part of component `i` cut off by `_split`
        (default: the whole component)."""
        cfg = self.config
        g, binary = level.g, level.binary
        x, y, w, h = box if box is not None else (int(v) for v in level.stats[i][:4])
        size = float(max(w, h))
        self._why, self._claimed, self._card_refusal, self._spared = "card", shape, "", False
        # the card, with room for whatever lies on it within `surround` of the mark
        pad = math.ceil(3 * cfg.surround * size) + 2
        x0, y0 = max(0, x - pad), max(0, y - pad)
        x1, y1 = min(g.shape[1], x + w + pad), min(g.shape[0], y + h + pad)
        comp = np.zeros((y1 - y0, x1 - x0), np.uint8)
        comp[y - y0 : y - y0 + h, x - x0 : x - x0 + w] = own
        shift = np.array([[[x - x0 - 1, y - y0 - 1]]], np.int32)
        blob = _Blob(blob.outer + shift, [c + shift for c in blob.holes], blob.area, blob.size)
        filled = np.zeros_like(comp)
        cv2.drawContours(filled, [blob.outer], -1, 255, cv2.FILLED)
        bin_roi = binary[y0:y1, x0:x1]
        g_roi = g[y0:y1, x0:x1]
        ink = cv2.mean(g_roi, mask=comp)[0]
        extent = math.sqrt(max(cv2.contourArea(cv2.convexHull(blob.outer)), 1.0))
        dist = _distance(filled, (x - x0, y - y0, w, h), _reach(cfg, extent))
        paper = _on_card(g_roi, filled, ink, extent, dist, cfg, self._rescues(shape), danger=shape is not Shape.O)
        if paper == "texture" and shape is Shape.O and cfg.safe_texture_window > 0 and self.verifier is not None:
            # the O's card against its own local mean: kept so, the O needs the verifier's `safe_card_sure`
            paper = _on_card(g_roi, filled, ink, extent, dist, cfg, self._rescues(shape), window=cfg.safe_texture_window)
            self._spared = not isinstance(paper, str) and cfg.safe_card_sure > 0
        # an X claimed only above X_SOLIDITY was a loose candidate before round vision65b: without x_solidity_veto its
        # refusal leaves the proposer free there, as it was then
        vetoes = cfg.x_solidity_veto or named or shape is not Shape.X or blob.area <= X_SOLIDITY * extent**2
        if isinstance(paper, str):
            self._card_refusal = paper
            if not vetoes:
                return None
            if paper != "faint" or (
                cfg.faint_veto
                and (  # at -255 every faint component vetoes: no need to measure its band again
                    cfg.faint_veto_contrast <= -255.0
                    or _band_contrast(g_roi, ink, extent, dist, cfg) >= cfg.faint_veto_contrast
                )
            ):
                self._vetoes.append(_up((x, y, w, h), level.f))
            return None
        if shape is Shape.O and cfg.safe_margin > 0:
            # a false O would lift a danger: the safe mark must also have the wide clear margin
            margin = _clear_margin(g_roi, bin_roi, filled, ink, extent, dist, cfg)
            self._spared = self._spared or (margin == "card" and cfg.safe_card_sure > 0)
            if not margin or (self._spared and self.verifier is None):
                self._why = "O margin"
                self._vetoes.append(_up((x, y, w, h), level.f))
                return None
        self._why = "hole"
        if blob.holes:
            # a hole is paper: empty of other ink and about as bright as the card (a big filled disc
            # or triangle, hollowed by the local threshold, has a dark 'hole')
            holes = cv2.subtract(filled, comp)
            n_hole = cv2.countNonZero(holes)
            if n_hole == 0:
                return None
            hole_level = cv2.minMaxLoc(g_roi, mask=holes)[1]  # brightest: a small hole is blurred
            if hole_level - ink < cfg.min_hole_contrast * (paper - ink):
                # a dark hole: only a filled triangle may have one, and then it is all ink
                hole_mean = cv2.mean(g_roi, mask=holes)[0]
                if shape is not Shape.TRIANGLE or hole_mean - ink > 0.35 * (paper - ink):
                    return None
            elif cv2.countNonZero(cv2.bitwise_and(holes, bin_roi)) > 0.03 * n_hole:
                return None
        if conf < (cfg.loose_confidence if named else cfg.min_confidence):
            self._why = "confidence"
            return None
        if self._text_line(level, i):
            self._why = "text line"
            if vetoes:
                self._vetoes.append(_up((x, y, w, h), level.f))
            return None
        self._why = "kept"
        return Detection(shape, conf, (x, y, w, h))

    def _split(
        self, level: _Level, i: int, own: np.ndarray, box: Box, loose_part: bool = True
    ) -> Detection | _Pending | None:
        """Component `i` (mask `own` over its `box`), in which the shape tests found no mark: is it a
        mark joined to a lighter finger? Take away its parts lighter than the ink (`DetectorConfig.split`)
        and judge the largest parts left like components of their own: the first X or TRIANGLE that
        passes the card tests (or that the verifier may rescue) is returned, else the first part fit to
        be a loose candidate (if `loose_part`), else None (`_why` is then meaningless)."""
        cfg = self.config
        x, y, w, h = box
        if (
            not cfg.split
            or max(w, h) < cfg.split_min
            or level.f not in cfg.split_levels
            or self._seen is not None
        ):
            return None
        g_box = level.g[y : y + h, x : x + w]
        # ink on light paper: most of its box is much lighter than the component (a mark joined to a
        # card's edge has the background all round it, but the card inside its box)
        if cv2.mean(g_box)[0] - cv2.mean(g_box, mask=own)[0] < cfg.split_surround:
            return None
        # two grey levels in one component: dark ink and a lighter finger (Otsu's split), each a
        # sizeable share of it and clearly apart
        hist = cv2.calcHist([g_box], [0], own, [256], [0, 256]).ravel().astype(np.float64)
        t, dark_mean, light_mean, dark_share, explained = _otsu(hist)
        if not (
            cfg.split_share[0] <= dark_share <= 1 - cfg.split_share[1]
            and light_mean - dark_mean >= cfg.split_contrast
            and explained >= cfg.split_explained
        ):
            return None
        keep = cv2.bitwise_and(own, cv2.inRange(g_box, 0, t))
        _, labels, stats = _components(keep)
        loose: _Pending | None = None
        H, W = level.g.shape
        for j in np.argsort(-stats[:, 4])[: cfg.split_parts + 1]:
            if j == 0:
                continue
            sx, sy, sw, sh, area = (int(v) for v in stats[j])
            if min(sw, sh) < cfg.min_size or max(sw, sh) > cfg.max_aspect * min(sw, sh):
                continue
            if x + sx == 0 or y + sy == 0 or x + sx + sw == W or y + sy + sh == H:  # the finger's side
                continue
            if max(sw, sh) < 0.3 * max(w, h):  # a crumb of the finger's outline
                continue
            if not 0.08 <= area / (sw * sh) <= 0.62:
                continue
            part = cv2.inRange(labels[sy : sy + sh, sx : sx + sw], int(j), int(j))
            blob = _blob(
                cv2.copyMakeBorder(part, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0), float(max(sw, sh))
            )
            if blob is None:
                continue
            judged = _classify(blob, cfg)
            sub = (x + sx, y + sy, sw, sh)
            if judged is None or judged[0] is Shape.O:
                if (
                    loose is None
                    and loose_part
                    and "loose" in cfg.split
                    and max(sw, sh) <= cfg.split_shrink * max(w, h)
                    and self._loose(level.g, part, blob, sub, any_size=True)
                ):
                    loose = _Pending(level, i, sub, None, blob=blob, own=part, part=True)
                continue
            shape, conf = judged
            det = self._finish(level, i, blob, part, shape, conf, box=sub)  # type: ignore[arg-type]
            if det is not None:
                return det
            if self.verifier is not None and self._rescuable(shape, level, i):
                return _Pending(level, i, sub, shape, det=Detection(shape, conf, sub), rescue=True)
        return loose

    def _loose(self, g: np.ndarray, own: np.ndarray, blob: _Blob, box: Box, any_size: bool = False) -> bool:
        """A component the shape tests found no mark in: is it ink on a light, plain surround, for the
        verifier to name (stricter thresholds)? While harvesting training candidates (no verifier) it
        is recorded with no claimed shape and goes no further (False)."""
        cfg = self.config
        if not cfg.loose or len(blob.holes) > 1 or (self.verifier is None and self._seen is None):
            return False
        x, y, w, h = box
        if self._f == 1 and max(w, h) > cfg.loose_max_size and not any_size:
            return False
        around = _surround(g, box)
        if around is None:
            return False
        ring, spread = around
        ink = cv2.mean(g[y : y + h, x : x + w], mask=own)[0]
        contrast = ring - ink
        if (
            contrast < cfg.loose_contrast
            or ink > max(cfg.max_contrast_ratio, cfg.danger_contrast_ratio) * ring
            or spread > cfg.loose_texture * contrast
        ):
            return False
        if self._seen is not None:
            self._seen.append(Candidate(None, _up(box, self._f), crops(g, box)))
        return self.verifier is not None


_LEVELS = np.arange(256, dtype=np.float64)


def _otsu(hist: np.ndarray) -> tuple[int, float, float, float, float]:
    """Otsu's threshold of a 256-bin grey-level histogram: the level t that best splits it into a dark
    (<= t) and a light class, their mean levels, the dark class's share of the count and the share of
    the grey-level variance the split explains (near 1: two clear levels)."""
    n = hist.sum()
    w0 = np.cumsum(hist)
    s0 = np.cumsum(hist * _LEVELS)
    w1 = n - w0
    with np.errstate(divide="ignore", invalid="ignore"):
        m0 = s0 / w0
        m1 = (s0[-1] - s0) / w1
        between = w0 * w1 * (m0 - m1) ** 2
    between[~np.isfinite(between)] = -1.0
    t = int(np.argmax(between))
    if n <= 0 or between[t] <= 0:
        return 255, 0.0, 0.0, 1.0, 0.0
    total = float((hist * _LEVELS**2).sum()) - s0[-1] ** 2 / n
    return t, float(m0[t]), float(m1[t]), float(w0[t] / n), float(between[t] / n / max(total, 1e-9))


def _surround(g: np.ndarray, box: Box) -> tuple[float, float] | None:
    """The mean grey level and its spread in a frame 10 % of its size wide around `box` (None if the
    frame is empty)."""
    x, y, w, h = box
    m = max(2, math.ceil(0.1 * max(w, h)))
    x0, y0 = max(0, x - m), max(0, y - m)
    x1, y1 = min(g.shape[1], x + w + m), min(g.shape[0], y + h + m)
    region = g[y0:y1, x0:x1]
    inner = g[y : y + h, x : x + w]
    n_ring = region.size - inner.size
    if n_ring <= 0:
        return None
    # sums of grey levels and of their squares, in doubles (OpenCV: no float32 rounding, no copies)
    ring_sum = cv2.sumElems(region)[0] - cv2.sumElems(inner)[0]
    ring_sq = cv2.norm(region, cv2.NORM_L2SQR) - cv2.norm(inner, cv2.NORM_L2SQR)
    ring = ring_sum / n_ring
    return ring, math.sqrt(max(0.0, ring_sq / n_ring - ring * ring))


def middle_ink(g: np.ndarray, box: Box, middle: float) -> float:
    """The share of the ellipse of `middle` x `box`'s width and height at its centre that is darker than half-way
    from the ink of the ring round it (the darkest tenth of the band from 0.55 to 1.1 x the box's half width and
    height) to the middle's paper (its median): about 0 for an O's blank hole. 1 where the middle is not
    `_MIDDLE_CONTRAST` grey levels lighter than that ink (a disc, a dark patch: no hole to see) or the box is all
    but outside the frame (`DetectorConfig.propose_o_clear`)."""
    x, y, w, h = box
    cx, cy = x + w / 2, y + h / 2
    x0, y0 = max(0, math.floor(cx - 0.55 * w)), max(0, math.floor(cy - 0.55 * h))
    x1, y1 = min(g.shape[1], math.ceil(cx + 0.55 * w)), min(g.shape[0], math.ceil(cy + 0.55 * h))
    if x1 - x0 < 3 or y1 - y0 < 3:
        return 1.0
    yy, xx = np.ogrid[y0:y1, x0:x1]
    e = ((xx + 0.5 - cx) / max(1.0, w / 2)) ** 2 + ((yy + 0.5 - cy) / max(1.0, h / 2)) ** 2  # 1 on the box's ellipse
    roi = g[y0:y1, x0:x1]
    inner = roi[e <= middle**2]
    band = roi[(e >= 0.55**2) & (e <= 1.1**2)]
    if inner.size < 4 or band.size < 4:
        return 1.0
    paper = float(np.median(inner))
    ink = float(np.percentile(band, 10))
    if paper - ink < _MIDDLE_CONTRAST:
        return 1.0
    return float(np.count_nonzero(inner < (paper + ink) / 2)) / inner.size


_MIDDLE_CONTRAST = 20.0
"""grey levels a proposed O's middle must be lighter than its ring's ink (`middle_ink`)"""


def hole_islands(g: np.ndarray, box: Box) -> float:
    """The share of `box`'s area covered by islands of ink in an O's hole: the blobs of ink (`_box_ink`) other than
    the largest, each at least `_ISLAND_LEAST` of the box, whose bounding boxes lie wholly inside the ellipse of
    `_ISLAND_REACH` x the box's width and height at its centre. About 0 for an O mark, whose hole is blank card (a
    fingertip or a card's edge reaching in comes from outside the middle); a face's eyes and mouth are islands. 0
    where the box shows no ink to split."""
    ink = _box_ink(g, box)
    if ink is None:
        return 0.0
    (x0, y0), _, stats = ink
    if len(stats) < 3:
        return 0.0
    x, y, w, h = box
    area = float(w * h)
    cx, cx_half = x + w / 2 - x0, _ISLAND_REACH * w / 2
    cy, cy_half = y + h / 2 - y0, _ISLAND_REACH * h / 2
    ring = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    total = 0
    for i in range(1, len(stats)):
        bx, by, bw, bh, a = (int(v) for v in stats[i])
        if i == ring or a < _ISLAND_LEAST * area:
            continue
        corners = ((bx, by), (bx + bw, by), (bx, by + bh), (bx + bw, by + bh))
        if all(((px - cx) / cx_half) ** 2 + ((py - cy) / cy_half) ** 2 <= 1 for px, py in corners):
            total += a
    return total / area


_ISLAND_LEAST = 0.002
"""the smallest blob `hole_islands` counts, as a share of the box (a speck of noise or JPEG is smaller)"""
_ISLAND_REACH = 0.8
"""the middle `hole_islands` looks in, as a share of the box's width and height (an O's hole with the tuning
generator's strokes is 0.6-0.8 of its width)"""


@dataclass(frozen=True)
class BlobShape:
    """The outline of the solid ink blob at a proposal's middle (`middle_blob`)."""

    triangle_fill: float  # its area over its minimum enclosing triangle's: about 1 for a triangle, 0.6 for a disc
    roundness: float  # `_ellipse_residual` of its outline: 0 for an ellipse, about 0.08-0.1 for a triangle
    solidity: float  # its area over its convex hull's


def middle_blob(g: np.ndarray, box: Box) -> BlobShape | None:
    """The shape of the one solid blob of ink at the middle of `box`: the ink (Otsu's split of the box and a tenth of
    its size round it) connected to the middle fifth of the box, if it has no hole, lies inside the region (does not
    run on past it, as a finger, a hand or a bigger shape would) and is at least 6 px across. None otherwise, and where
    the region shows under `_MIDDLE_CONTRAST` grey levels (`DetectorConfig.propose_t_fill`)."""
    ink = _box_ink(g, box)
    if ink is None:
        return None
    (x0, y0), labels, stats = ink
    x, y, w, h = box
    cx, cy = x + w / 2 - x0, y + h / 2 - y0  # the box's centre in the region
    rows = slice(max(0, int(cy - 0.1 * h)), max(1, math.ceil(cy + 0.1 * h)))
    cols = slice(max(0, int(cx - 0.1 * w)), max(1, math.ceil(cx + 0.1 * w)))
    mid = labels[rows, cols]  # the middle fifth of the box
    ids, counts = np.unique(mid[mid > 0], return_counts=True)
    if not len(ids):
        return None
    i = int(ids[np.argmax(counts)])
    if not _lies_inside(stats, i, labels.shape):
        return None
    outer = _hole_free_outline(labels, i)
    if outer is None:  # a hole: an outline, judged by its shape tests, not here
        return None
    area = cv2.contourArea(outer)
    hull = cv2.contourArea(cv2.convexHull(outer))
    roundness = _ellipse_residual(outer)
    if area <= 0 or hull <= 0 or roundness is None:
        return None
    return BlobShape(_triangle_fill(outer, area), roundness, area / hull)


@dataclass(frozen=True)
class OpenSide:
    """The least-covered side of an outline taken for a triangle (`open_side`)."""

    cover: float  # the share of points along it within reach of the outline's ink (about 1: drawn; 0.1-0.5: open)
    shade: float  # how dark its middle is, from the paper round the outline (0) to the outline's ink (1)


_BOX_MARGIN = 0.1
"""the paper round a box, as a share of its size, that `_box_ink` takes with it unless told otherwise (`middle_blob`,
`hole_islands`, `notches`; `open_proposal` passes `DetectorConfig.propose_open_margin` to `box_outline`)"""


def _box_ink(
    g: np.ndarray, box: Box, margin: float = _BOX_MARGIN
) -> tuple[tuple[int, int], np.ndarray, np.ndarray] | None:
    """The ink of `box` and `margin` x its size round it (Otsu's split of that region), as connected components: the
    region's origin in `g`, its labels and their stats. None where the region is under 8 px a side or shows under
    `_MIDDLE_CONTRAST` grey levels."""
    x, y, w, h = box
    m = max(2, math.ceil(margin * max(w, h)))
    x0, y0 = max(0, x - m), max(0, y - m)
    x1, y1 = min(g.shape[1], x + w + m), min(g.shape[0], y + h + m)
    roi = g[y0:y1, x0:x1]
    if roi.shape[0] < 8 or roi.shape[1] < 8 or int(roi.max()) - int(roi.min()) < _MIDDLE_CONTRAST:
        return None
    _, ink = cv2.threshold(roi, 0, 255, cv2.THRESH_BINARY_INV | cv2.THRESH_OTSU)
    _, labels, stats, _ = cv2.connectedComponentsWithStats(ink, connectivity=8)
    return (x0, y0), labels, stats


def box_outline(g: np.ndarray, box: Box, margin: float = _BOX_MARGIN) -> np.ndarray | None:
    """The outline (in `g`'s pixels) of the largest blob of ink in `box` and `margin` x its size round it (`_box_ink`)
    that lies inside that region (does not run on past it) and is at least 6 px across, if it has no hole; None
    otherwise (an outline's hole: judged by the verifier alone). What `open_side` judges of a proposal, which has no
    component of its own (`DetectorConfig.propose_open_side`, `propose_open_margin`)."""
    blob = _largest_inside(g, box, margin)
    if blob is None:
        return None
    (x0, y0), labels, stats, i = blob
    outer = _hole_free_outline(labels, i)
    return None if outer is None else outer + np.array([x0, y0], np.int32)


def _largest_inside(
    g: np.ndarray, box: Box, margin: float = _BOX_MARGIN
) -> tuple[tuple[int, int], np.ndarray, np.ndarray, int] | None:
    """The largest blob of ink in `box` and `margin` x its size round it (`_box_ink`) that lies inside that region
    (`_lies_inside`): the region's origin in `g`, its labels and stats, and the blob's label; None if there is none
    (`box_outline`, `notches`)."""
    ink = _box_ink(g, box, margin)
    if ink is None:
        return None
    origin, labels, stats = ink
    inside = [i for i in range(1, len(stats)) if _lies_inside(stats, i, labels.shape)]
    if not inside:
        return None
    return origin, labels, stats, max(inside, key=lambda j: stats[j, cv2.CC_STAT_AREA])


def _lies_inside(stats: np.ndarray, i: int, region: tuple[int, ...]) -> bool:
    """Whether blob `i` of a region of this shape (rows, columns) touches none of its edges (does not run on past
    it, as a finger, a hand or a bigger shape would) and is at least 6 px across (`middle_blob`, `_largest_inside`)."""
    bx, by, bw, bh = (int(v) for v in stats[i, :4])
    return bx > 0 and by > 0 and bx + bw < region[1] and by + bh < region[0] and max(bw, bh) >= 6


def _hole_free_outline(labels: np.ndarray, i: int) -> np.ndarray | None:
    """The outline of blob `i` in `labels`, or None if it has a hole."""
    contours, _ = cv2.findContours((labels == i).astype(np.uint8), cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    return contours[0] if len(contours) == 1 else None


def open_side(g: np.ndarray, outer: np.ndarray, reach: float = 0.08, samples: int = 17) -> OpenSide | None:
    """How much of its least-covered side an outline without a hole (`outer`, in `g`'s pixels) draws, as a triangle,
    and how dark that side is in `g`. Cover: the share of points along each side of the outline's minimum enclosing
    triangle (from a tenth to nine tenths of the side) that lie within `reach` times the outline's larger extent (at
    least 2 px) of its ink, the lowest of the three. Shade: at five places along that side's middle fifth, the darkest
    grey of `g` on a line across it (a tenth of the extent each way); their median against the paper (the brightest
    tenth of the region round the outline and its triangle) and the outline's ink (the darkest twentieth under it): 0
    where the side is as light as the paper, 1 where it is as dark as the ink (and where `g` holds none of it). A
    filled triangle, or an outline broken by a gap, draws about all of each side; two strokes meeting at an angle (a
    clock's hands, a check mark, a chevron), whose hull is a triangle too, leave the third side open and as light as
    the face they lie on, while a faint blurred side or a finger across one is darker. None for a degenerate
    outline."""
    pts = outer.reshape(-1, 2).astype(np.float32)
    try:
        _, tri = cv2.minEnclosingTriangle(pts.reshape(-1, 1, 2))
    except cv2.error:
        return None
    if tri is None:
        return None
    corners = tri.reshape(3, 2).astype(np.float64)
    extent = float(max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1])))
    x0, y0 = np.floor(np.minimum(pts.min(axis=0), corners.min(axis=0))).astype(int) - 2
    x1, y1 = np.ceil(np.maximum(pts.max(axis=0), corners.max(axis=0))).astype(int) + 3
    size = (int(y1 - y0), int(x1 - x0))
    if extent < 4 or size[0] * size[1] > 16 * (extent + 5) ** 2:  # a degenerate triangle far larger than the outline
        return None
    origin = np.array([x0, y0])
    ink_mask = np.zeros(size, np.uint8)
    cv2.drawContours(ink_mask, [outer.reshape(-1, 1, 2).astype(np.int32) - origin.astype(np.int32)], -1, 255, cv2.FILLED)
    far = cv2.distanceTransform(255 - ink_mask, cv2.DIST_L2, 3)  # each pixel's distance to the ink
    limit = max(2.0, reach * extent)
    t = np.linspace(0.1, 0.9, samples)[:, None]
    covers = []
    for k in range(3):
        a, b = corners[k] - origin, corners[(k + 1) % 3] - origin
        on = a + t * (b - a)
        cols = np.clip(np.round(on[:, 0]).astype(int), 0, size[1] - 1)
        rows = np.clip(np.round(on[:, 1]).astype(int), 0, size[0] - 1)
        covers.append(float(np.mean(far[rows, cols] <= limit)))
    k = int(np.argmin(covers))
    a, b, c = corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]
    inward = (c - (a + b) / 2) / max(1e-6, float(np.hypot(*(c - (a + b) / 2))))
    across = np.linspace(-0.1, 0.1, 7) * extent  # a band across the side, a tenth of the extent each way
    darkest = []
    for u in np.linspace(0.4, 0.6, 5):  # the side's middle fifth
        line = (a + u * (b - a))[None, :] + across[:, None] * inward[None, :]
        dark = _darkest_at(g, line)
        if dark is not None:
            darkest.append(dark)
    ox, oy = int(x0), int(y0)
    h, w = g.shape[:2]
    sx0, sy0, sx1, sy1 = max(0, ox), max(0, oy), min(w, ox + size[1]), min(h, oy + size[0])
    region = g[sy0:sy1, sx0:sx1]
    under = region[ink_mask[sy0 - oy : sy1 - oy, sx0 - ox : sx1 - ox] > 0]
    if not darkest or not under.size:  # the side lies outside the frame: nothing to call open
        return OpenSide(covers[k], 1.0)
    ink, paper = float(np.percentile(under, 5)), float(np.percentile(region, 90))
    return OpenSide(covers[k], float(np.clip((paper - np.median(darkest)) / max(1.0, paper - ink), 0.0, 1.0)))


def _darkest_at(g: np.ndarray, points: np.ndarray) -> float | None:
    """The darkest of `g`'s grey levels at `points` (x, y) that lie inside it; None if none does."""
    cols, rows = np.round(points[:, 0]).astype(int), np.round(points[:, 1]).astype(int)
    inside = (cols >= 0) & (rows >= 0) & (cols < g.shape[1]) & (rows < g.shape[0])
    if not inside.any():
        return None
    return float(g[rows[inside], cols[inside]].min())


@dataclass(frozen=True)
class Notches:
    """The deep notches of the largest blob of ink in a box (`notches`)."""

    count: int  # notches at least `depth` times the blob's extent deep
    widest_gap: float  # the widest angle (degrees) between two neighbouring notches, seen from the blob's centre
    inner: float  # the nearest notch's distance from the centre, as a share of the outline's farthest point's

    def star(self, spread: float, inner: float) -> bool:
        """Whether these are a star's notches: five or more, no two neighbours more than `spread` times an even spacing
        apart, the nearest at least `inner` of the way out (`DetectorConfig.star_spread`, `star_inner`)."""
        return self.count >= 5 and self.widest_gap <= spread * 360.0 / self.count and self.inner >= inner


def notches(g: np.ndarray, box: Box, depth: float) -> Notches | None:
    """The notches of the largest blob of ink in `box` (`_box_ink`) that lies inside the region (does not run on past
    it) and is at least 6 px across, holes allowed: the convexity defects of its outer outline at least `depth` times
    its larger extent deep, the widest angle between two of them neighbouring round the blob's centre (360 for one; 0
    for none) and how far out the nearest lies. An X has four deep notches, where its strokes cross, and a triangle
    none, while a five-pointed star has five, evenly spread, about half-way out (`DetectorConfig.star_depth`). None
    where there is no such blob or its outline is degenerate."""
    blob = _largest_inside(g, box)
    if blob is None:
        return None
    _, labels, stats, i = blob
    contours, _ = cv2.findContours((labels == i).astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    outer = max(contours, key=cv2.contourArea)
    if len(outer) < 8:
        return None
    try:
        defects = cv2.convexityDefects(outer, np.sort(cv2.convexHull(outer, returnPoints=False), axis=0))
    except cv2.error:  # OpenCV refuses a hull it finds not monotonous even sorted (a self-touching outline)
        return None
    extent = float(max(stats[i, cv2.CC_STAT_WIDTH], stats[i, cv2.CC_STAT_HEIGHT]))
    if defects is None:
        return Notches(0, 0.0, 0.0)
    defects = defects.reshape(-1, 4)
    deep = defects[defects[:, 3] / 256.0 >= depth * extent, 2]  # the deepest point of each deep notch
    if not len(deep):
        return Notches(0, 0.0, 0.0)
    m = cv2.moments(outer)
    if m["m00"] <= 0:
        return None
    centre = np.array([m["m10"] / m["m00"], m["m01"] / m["m00"]])
    at = outer[deep, 0, :].astype(np.float64) - centre
    angles = np.sort(np.degrees(np.arctan2(at[:, 1], at[:, 0])))
    gaps = np.diff(np.concatenate([angles, angles[:1] + 360.0]))
    reach = float(np.hypot(*(outer[:, 0, :] - centre).T).max())
    return Notches(len(deep), float(gaps.max()), float(np.hypot(*at.T).min()) / max(reach, 1e-6))


def _reach(cfg: DetectorConfig, extent: float) -> float:
    """The farthest distance from a mark's outline that any context test looks at (`_on_card`,
    `_letter_beside`, `_clear_margin`), for a mark of this extent: `_distance` is exact up to it."""
    halo = max(2.5, cfg.border * extent)
    return max(
        3.0,
        1.5 + cfg.border * extent,
        halo + 1.0,
        extent * max(cfg.surround, cfg.letter_gap, cfg.clutter_radius, cfg.safe_margin),
    )


def _distance(filled: np.ndarray, box: Box, reach: float) -> np.ndarray:
    """Every pixel's distance to the nearest pixel of `filled` (the mark's filled outline, inside `box`
    of this region): OpenCV's 3x3 chamfer approximation of the Euclidean distance, computed only on
    the part of the region within `reach` of the box and infinite beyond it, where no context test
    looks (the card region is about three times larger: most of the cost saved).

    Where it is finite it is the whole region's transform: the 3x3 chamfer distance is the cheapest
    path of straight (0.955) and diagonal (1.3693) steps to the outline, such a path never leaves the
    rectangle spanned by its two ends, which lies in the cut, and outside the cut every pixel is more
    than `reach` away (each step moves at most one pixel in x and y). Only the float32 rounding of
    equally short paths can differ, by a unit or two in the last place (tests/vision); the detections
    on 1,000 tuning and 2,000 held-out frames were the same, box for box (the vision README)."""
    x, y, w, h = box
    m = math.ceil(reach / 0.955) + 2
    H, W = filled.shape
    x0, y0, x1, y1 = max(0, x - m), max(0, y - m), min(W, x + w + m), min(H, y + h + m)
    dist = np.full(filled.shape, np.inf, np.float32)
    dist[y0:y1, x0:x1] = cv2.distanceTransform(cv2.bitwise_not(filled[y0:y1, x0:x1]), cv2.DIST_L2, 3)
    return dist


def _on_card(
    g_roi: np.ndarray,
    filled: np.ndarray,
    ink: float,
    extent: float,
    dist: np.ndarray,
    cfg: DetectorConfig,
    may_rescue: bool,
    danger: bool = False,
    window: float | None = None,
) -> float | str:
    """The card test: is the mark (filled outline `filled`, mean grey `ink`, `extent`, every pixel's
    distance `dist` to its outline from `_distance`) printed on a plain light card? Returns the card's
    grey level, or the first test that refused it, in this order: "band" (no band), "faint" (less
    than `min_contrast` between ink and paper: a shadow or a crease), "letter" (a letter-sized shape
    beside it: a word; "beside" instead where none is a letter of the mark's word by `letter_other_ink` and
    `letter_card`), "ratio" (the ink not dark enough next to the paper: `max_contrast_ratio`, or for a `danger`
    mark, an X or triangle, `danger_contrast_ratio` where set), "band" (the band not
    paper), "texture" (the card near it not plain), "ink" (other ink on the card). The order matters
    only for the verifier's rescue (`DetectorConfig.card_rescue`): the tests it may overrule come after
    the two it may not. "beside" is looked for only where the rescue could overrule it (`may_rescue`: the
    mark is an X or triangle; and `card_rescue_from` names "beside"): elsewhere it would be refused all the
    same, and the second look costs time (round vision36c). `window`, where given, is the texture test's window in
    place of the config's (an O's card asked again with `safe_texture_window`).

    The card is found from the mark outwards, not assumed to be a ring of fixed width: a band of
    `border` x the mark's extent just outside its outline must be paper (light, plain, clearly
    brighter than the ink); the card is then every light pixel connected to that band. Within
    `surround` x the extent, that card must be plain, and anything dark that the card encloses (other
    ink on it: the next letters of a word, the stones of gravel around a 'stone ring') may cover at
    most `max_surround_ink` of it. Dark things that reach in from outside the card (fingers, the
    background beyond a narrow card edge) are not on the card and do not count against the mark.
    The extent is sqrt(hull area), not the box: a rotated X's box is 1.4 times wider, its card is not.
    """
    band, band_n, paper = _band_paper(g_roi, dist, extent, cfg)
    if paper is None:
        return "band"
    if paper < 20 or paper - ink < cfg.min_contrast:
        return "faint"
    dark = ink + 0.3 * (paper - ink)
    cut = ink + 0.5 * (paper - ink)
    same_ink = max(8.0, cfg.letter_ink * (paper - ink)) if cfg.letter_ink > 0 else math.inf
    if cfg.letter_gap > 0 and _letter_beside(
        g_roi, filled, dist, extent, dark, cut, cfg.letter_gap, ink, same_ink
    ):
        if (cfg.letter_other_ink > 0 or cfg.letter_card) and may_rescue and "beside" in cfg.card_rescue_from:
            # is any of them a letter of the mark's word: in its ink, on its card? If not, "beside"
            other_ink = max(8.0, cfg.letter_other_ink * (paper - ink)) if cfg.letter_other_ink > 0 else same_ink
            mine = None
            if cfg.letter_card:
                near = None  # with `letter_card_paper`, the card is only the light regions of about the paper's grey
                if cfg.letter_card_paper > 0:
                    tol = cfg.letter_card_paper * (paper - ink)
                    near = cv2.inRange(g_roi, max(0.0, paper - tol), min(255.0, paper + tol))
                mine = _card(g_roi, filled, band, cut, near)[1]
            if not _letter_beside(g_roi, filled, dist, extent, dark, cut, cfg.letter_gap, ink, other_ink, mine):
                return "beside"
        return "letter"
    limit = cfg.danger_contrast_ratio if danger and cfg.danger_contrast_ratio > 0 else cfg.max_contrast_ratio
    if ink > limit * paper:
        return "ratio"
    band_paper, card = _card(g_roi, filled, band, cut)
    if cv2.countNonZero(band_paper) < cfg.min_band_paper * band_n:
        return "band"
    near = cv2.inRange(dist, 1.5, max(3.0, cfg.surround * extent))
    card_near = cv2.bitwise_and(card, near)
    mean, std = cv2.meanStdDev(g_roi, mask=card_near)
    most = cfg.max_margin_texture * (paper - ink)
    if window is None:
        window = cfg.danger_texture_window if danger and cfg.danger_texture_window > 0 else cfg.texture_window
    if float(std[0][0]) > most and (
        window <= 0 or _local_spread(g_roi, card_near, max(3, round(window * extent))) > most
    ):
        return "texture"
    inside, labels = _enclosed(card, filled)
    if inside.any():
        close = _beyond_halo(dist, extent, cfg.clutter_radius, cfg)
        on_card = int(np.count_nonzero(inside[labels[close]]))
        if on_card > cfg.max_surround_ink * max(1, cv2.countNonZero(card_near)):
            return "ink"
    return float(mean[0][0])


def _local_spread(g: np.ndarray, mask: np.ndarray, window: int) -> float:
    """The standard deviation over `mask` of `g` less each pixel's mean over the masked pixels of a `window` x `window`
    box round it (a normalised box filter: the mask's own pixels only, so ink beside the card does not pull it down):
    the grain of the masked region, without what changes over more than the window (`DetectorConfig.texture_window`)."""
    on = (mask > 0).astype(np.float32)
    grey = g.astype(np.float32)
    local = cv2.blur(grey * on, (window, window)) / np.maximum(cv2.blur(on, (window, window)), 1e-6)
    return float((grey - local)[mask > 0].std())


def _band_paper(
    g_roi: np.ndarray, dist: np.ndarray, extent: float, cfg: DetectorConfig
) -> tuple[np.ndarray, int, float | None]:
    """The mark's border band (`_border_band`), its pixel count and the paper's grey level there: the band's median,
    None where there is no band."""
    band = _border_band(dist, extent, cfg)
    band_n = cv2.countNonZero(band)
    return band, band_n, _masked_median(g_roi, band, band_n) if band_n else None


def _band_contrast(g_roi: np.ndarray, ink: float, extent: float, dist: np.ndarray, cfg: DetectorConfig) -> float:
    """How many grey levels lighter than the mark's `ink` the paper in its border band is, as `_on_card` measures it
    (-255 where there is no band): negative where the mark lies within something darker."""
    paper = _band_paper(g_roi, dist, extent, cfg)[2]
    return paper - ink if paper is not None else -255.0


def _border_band(dist: np.ndarray, extent: float, cfg: DetectorConfig) -> np.ndarray:
    """The band just outside the mark's outline, `border` x its extent wide (at least 3 px), where its paper is
    looked for; it skips the blurred outline itself (the first 1.5 px)."""
    return cv2.inRange(dist, 1.5, max(3.0, 1.5 + cfg.border * extent))


def _enclosed(card: np.ndarray, filled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dark things enclosed by the `card` (not reaching the edge of the region looked at): other ink on it. Returns
    which of the 4-connected regions neither card nor mark (`filled`) are enclosed, by label, and the labels."""
    other = cv2.bitwise_not(cv2.bitwise_or(card, filled))
    n, labels = _labels(other, connectivity=4)
    inside = np.ones(n, bool)  # no pixel on the region's edge
    for edge in (labels[0], labels[-1], labels[:, 0], labels[:, -1]):
        inside[edge] = False
    inside[0] = False
    return inside, labels


def _beyond_halo(dist: np.ndarray, extent: float, reach: float, cfg: DetectorConfig) -> np.ndarray:
    """The pixels from the border band out to `reach` x the mark's extent: nearer, the mark's own blurred edge is
    neither ink nor paper."""
    halo = max(2.5, cfg.border * extent)
    return (dist >= halo) & (dist <= max(halo + 1.0, reach * extent))


def _ranked(g: np.ndarray, mask: np.ndarray | None, ranks: list[int]) -> tuple[float, float]:
    """The grey levels at two 0-based `ranks` of a uint8 image's pixels sorted (those under `mask` if
    given), from their histogram: no copy, no sort."""
    counts = np.cumsum(cv2.calcHist([g], [0], mask, [256], [0, 256]).ravel())
    low, high = np.searchsorted(counts, ranks, side="right")
    return float(low), float(high)


def _masked_median(g: np.ndarray, mask: np.ndarray, n: int) -> float:
    """`np.median(g[mask > 0])` of a uint8 image over its `n` (> 0) masked pixels: the same value (the
    mean of the two middle levels for an even count)."""
    low, high = _ranked(g, mask, [(n - 1) // 2, n // 2])
    return (low + high) / 2.0


def _clear_margin(
    g_roi: np.ndarray,
    bin_roi: np.ndarray,
    filled: np.ndarray,
    ink: float,
    extent: float,
    dist: np.ndarray,
    cfg: DetectorConfig,
) -> str:
    """The strict context for the safe mark: every pixel within `safe_margin` x the extent of the
    outline is plain paper (at most `safe_max_ink` ink, spread at most `max_margin_texture` of the
    contrast), whatever the card's shape - fingers or a card edge there make the O wait. With
    `safe_margin_card`, an O this refuses may still pass `_card_margin`. Returns "strict", "card" (passed only on its
    card) or "" (refused)."""
    ring = cv2.inRange(dist, 1.5, max(3.0, cfg.safe_margin * extent))
    ring_n = cv2.countNonZero(ring)
    if ring_n > 0 and cv2.countNonZero(cv2.bitwise_and(bin_roi, ring)) <= cfg.safe_max_ink * ring_n:
        mean, std = cv2.meanStdDev(g_roi, mask=ring)
        if float(std[0][0]) <= cfg.max_margin_texture * max(1.0, float(mean[0][0]) - ink):
            return "strict"
    on_card = cfg.safe_margin_card and extent >= cfg.safe_card_extent
    return "card" if on_card and _card_margin(g_roi, bin_roi, filled, ink, extent, dist, cfg) else ""


def _card_margin(
    g_roi: np.ndarray,
    bin_roi: np.ndarray,
    filled: np.ndarray,
    ink: float,
    extent: float,
    dist: np.ndarray,
    cfg: DetectorConfig,
) -> bool:
    """The safe mark's clear margin judged on its card (rounds vision63b-63c; `safe_margin_card`): from the border
    band out to `safe_margin` x the extent, the ink (`bin_roi`, as the strict margin counts it) that the card encloses
    (`_enclosed`: other ink on it, not a card edge or a finger reaching in from beyond the card, which the card tests
    do not count either) covers at most `safe_card_ink` of the card's part of that ring with it; how plain the card
    is there, the card tests judged (`max_margin_texture`, out to `surround`). An O on a card whose border is narrower
    than the margin, the issue's case, passes; a stroke of ink on the card beside the O does not. Alone (round
    vision63b) it found 5 points of held-out O recall and made 5 more false O in 4,000 frames; with `safe_card_extent`
    and `safe_card_sure` (round vision63c) it found as much with no false O added, and is the default."""
    band, _, paper = _band_paper(g_roi, dist, extent, cfg)
    if paper is None:
        return False
    _, card = _card(g_roi, filled, band, ink + 0.5 * (paper - ink))
    inside, labels = _enclosed(card, filled)
    zone = _beyond_halo(dist, extent, cfg.safe_margin, cfg)
    card_n = int(np.count_nonzero(card[zone]))
    other_ink = int(np.count_nonzero(inside[labels[zone]] & (bin_roi[zone] > 0)))
    return card_n > 0 and other_ink <= cfg.safe_card_ink * (card_n + other_ink)


def _card(
    g_roi: np.ndarray, filled: np.ndarray, band: np.ndarray, cut: float, paper_like: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The paper in the mark's `band` (lighter than half-way from ink to paper, `cut`: for whole grey levels,
    > t is > floor(t); and within `paper_like`, a mask, if given), and the card: every such light region outside
    the mark (`filled`) that touches it."""
    light = cv2.threshold(g_roi, math.floor(cut), 255, cv2.THRESH_BINARY)[1]
    if paper_like is not None:
        light = cv2.bitwise_and(light, paper_like)
    light = cv2.bitwise_and(light, cv2.bitwise_not(filled))
    band_paper = cv2.bitwise_and(light, band)
    n, labels = _labels(light)
    touching = np.zeros(n, np.uint8)
    touching[labels[band_paper > 0]] = 255
    touching[0] = 0
    return band_paper, touching[labels]


def _letter_beside(
    g_roi: np.ndarray,
    filled: np.ndarray,
    dist: np.ndarray,
    extent: float,
    dark: float,
    paper_cut: float,
    gap: float,
    mark_ink: float = 0.0,
    same_ink: float = math.inf,
    card: np.ndarray | None = None,
) -> bool:
    """A word at any angle: another letter-sized shape as dark as the ink (mean grey at most `dark`)
    within `gap` x the mark's extent, made of strokes (not a solid blob), wholly in view of the
    region looked at (the background beyond a card's edge runs on out of it) and printed in the mark's
    ink (its mean grey within `same_ink` of `mark_ink`'s); with `card` (the mark's card, `_card`), printed on
    that card: the paper round it is the mark's, not another card's or a page's beyond the card's edge."""
    # as dark as `dark` (for whole grey levels, <= t is <= floor(t)), and not the mark itself
    ink = cv2.threshold(g_roi, math.floor(dark), 255, cv2.THRESH_BINARY_INV)[1]
    ink = cv2.bitwise_and(ink, cv2.bitwise_not(filled))
    n, labels, stats = _components(ink)
    if n <= 1:
        return False
    h, w = ink.shape
    sx, sy, sw, sh, area = (stats[:, k] for k in range(5))
    size, thin = np.maximum(sw, sh), np.minimum(sw, sh)
    letters = np.flatnonzero(
        (sx > 0)
        & (sy > 0)
        & (sx + sw < w)
        & (sy + sh < h)
        & (size >= 0.45 * extent)
        & (size <= 2.0 * extent)
        & (thin >= 0.15 * extent)
        & (area <= 0.65 * sw * sh)
    )
    for j in letters:
        x, y, cw, ch = (int(v) for v in stats[j, :4])
        mine = labels[y : y + ch, x : x + cw] == j
        nearest = float(dist[y : y + ch, x : x + cw][mine].min())
        if not 1.5 < nearest <= gap * extent:  # touching: part of the mark
            continue
        if same_ink < math.inf:
            box = g_roi[y : y + ch, x : x + cw]
            if abs(cv2.mean(box, mask=mine.view(np.uint8))[0] - mark_ink) > same_ink:
                continue
        # printed on the same paper: light all round it (unlike the background beyond a card's edge)
        if _paper_round(g_roi, labels, stats, int(j), paper_cut, card) >= 0.8:
            return True
    return False


def _clear_frames(
    binary: np.ndarray, stats: np.ndarray, margin: float = 0.04, max_ink: float = 0.4
) -> np.ndarray:
    """Cheap vectorised pre-test: little ink in a thin frame just outside each box (a mark sits on
    a card; a blob of texture or a letter in a word does not). Boolean mask over `stats` rows."""
    ii = cv2.integral(binary, sdepth=cv2.CV_32S)
    H, W = binary.shape
    x, y, w, h = (stats[:, k].astype(np.int64) for k in range(4))
    m = np.maximum(2, np.ceil(margin * np.maximum(w, h)).astype(np.int64))
    ox0, oy0 = np.maximum(0, x - m), np.maximum(0, y - m)
    ox1, oy1 = np.minimum(W, x + w + m), np.minimum(H, y + h + m)

    def box_sum(x0: np.ndarray, y0: np.ndarray, x1: np.ndarray, y1: np.ndarray) -> np.ndarray:
        return (ii[y1, x1] - ii[y0, x1] - ii[y1, x0] + ii[y0, x0]).astype(np.int64)

    ring = box_sum(ox0, oy0, ox1, oy1) - box_sum(x, y, x + w, y + h)
    ring_area = (ox1 - ox0) * (oy1 - oy0) - w * h
    return ring <= max_ink * 255 * np.maximum(ring_area, 1)


def _components(binary: np.ndarray, connectivity: int = 8) -> tuple[int, np.ndarray, np.ndarray]:
    """Connected components with stats; 16-bit labels are twice as fast and almost always enough.
    Which component gets which label depends on the algorithm: callers use labels only to tell
    components apart."""
    try:
        n, labels, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(
            binary, connectivity, cv2.CV_16U, cv2.CCL_SPAGHETTI
        )
    except cv2.error:  # more than 65535 components: a pathological (speckle) frame
        n, labels, stats, _ = cv2.connectedComponentsWithStats(binary, connectivity=connectivity)
    return n, labels, stats


def _labels(binary: np.ndarray, connectivity: int = 8) -> tuple[int, np.ndarray]:
    """`_components` without the stats (which can cost as much again)."""
    try:
        found = cv2.connectedComponentsWithAlgorithm(binary, connectivity, cv2.CV_16U, cv2.CCL_SPAGHETTI)
    except cv2.error:  # more than 65535 components
        found = cv2.connectedComponents(binary, connectivity=connectivity)
    return int(found[0]), found[1]


def working_gray(image: np.ndarray, max_side: int) -> tuple[np.ndarray, float]:
    """`image` in grey at most `max_side` on its longest side, and the factor its boxes scale back by: the detector
    works at about 640x480 whatever the camera gives, because its thresholds are tuned for that scale (and a large
    frame would cost more)."""
    gray = to_gray(image)
    if max(gray.shape) <= max_side:
        return gray, 1.0
    scale = max(gray.shape) / max_side
    size = (round(gray.shape[1] / scale), round(gray.shape[0] / scale))
    return cv2.resize(gray, size, interpolation=cv2.INTER_AREA), scale


def to_gray(image: np.ndarray) -> np.ndarray:
    """A uint8 single-channel view of a BGR, BGRA or grey image; ValueError for anything else."""
    if not isinstance(image, np.ndarray) or image.size == 0:
        raise ValueError("not an image: empty or not a numpy array")
    if image.dtype != np.uint8:
        raise ValueError(f"expected an 8-bit image, got dtype {image.dtype}")
    if image.ndim == 2:
        return image
    if image.ndim == 3 and image.shape[2] == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if image.ndim == 3 and image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    if image.ndim == 3 and image.shape[2] == 1:
        return image[:, :, 0]
    raise ValueError(f"unsupported image shape {image.shape}")


# ---------------------------------------------------------------------- features
def _blob(comp: np.ndarray, size: float) -> _Blob | None:
    contours, hier = cv2.findContours(comp, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_NONE)
    if not contours or hier is None:
        return None
    if len(contours) == 1:  # most components: one outline, no hole
        outer_idx, outer = 0, contours[0]
    else:
        parent = hier[0][:, 3].tolist()
        tops = [j for j in range(len(contours)) if parent[j] < 0]
        outer_idx = max(tops, key=lambda j: len(contours[j]))
        outer = contours[outer_idx]
    area = cv2.contourArea(outer)
    if area <= 0 or len(outer) < 8:
        return None
    holes = []
    if len(contours) > 1:
        holes = [
            contours[j]
            for j in range(len(contours))
            if parent[j] == outer_idx and cv2.contourArea(contours[j]) >= 0.02 * area
        ]
    return _Blob(outer, holes, area, size)


def _classify(b: _Blob, cfg: DetectorConfig) -> tuple[Shape, float] | None:
    if len(b.holes) == 1:
        return _ring_like(b)
    if not b.holes:
        hull = cv2.convexHull(b.outer)
        hull_area = cv2.contourArea(hull)
        if hull_area <= 0:
            return None
        return _cross(b, hull, hull_area, cfg.x_solidity) or _filled_triangle(
            b, hull_area, cfg.filled_solidity, cfg.filled_fill
        )
    return None


def _solid(b: _Blob | None, share: float) -> bool:
    """Whether `b` has no hole and fills at least `share` (under 1) of its convex hull: a solid shape."""
    if share >= 1 or b is None or b.holes:
        return False
    hull = cv2.contourArea(cv2.convexHull(b.outer))
    return hull > 0 and b.area / hull >= share


def _filled_triangle(b: _Blob, hull_area: float, solidity: float, min_fill: float) -> tuple[Shape, float] | None:
    """A solid triangle (on a card: the card test decides whether it is a mark or clutter); `hull_area`
    is the area of the outline's convex hull (`DetectorConfig.filled_solidity`, `filled_fill`)."""
    if b.area / hull_area < solidity:
        return None
    fill = _triangle_fill(b.outer, b.area)
    if fill < min_fill:
        return None
    return Shape.TRIANGLE, 1.0 - 0.5 * (1 - fill) / (1 - min_fill)


def _ring_like(b: _Blob) -> tuple[Shape, float] | None:
    hole = b.holes[0]
    hole_area = cv2.contourArea(hole)
    ratio = hole_area / b.area
    if not 0.08 <= ratio <= 0.85 or len(hole) < 6:
        return None
    offset = float(np.hypot(*(_centroid(b.outer) - _centroid(hole)))) / b.size
    # O: both contours are ellipses
    e_out = _ellipse_residual(b.outer)
    e_in = _ellipse_residual(hole) if e_out is not None and e_out <= 0.05 else None  # else: no O anyway
    if (
        e_out is not None
        and e_in is not None
        and e_out <= 0.05
        and e_in <= 0.08
        and offset <= 0.1
        and 0.31 <= ratio <= 0.8
        and _axis_ratio(b.outer) >= 0.3
    ):
        badness = max(e_out / 0.05, e_in / 0.08, offset / 0.1)
        return Shape.O, 1.0 - 0.5 * badness
    # TRIANGLE: both contours fill their minimum enclosing triangle
    if offset > 0.12 or ratio > 0.8:
        return None
    t_out = _triangle_fill(b.outer, b.area)
    if t_out < 0.8:
        return None
    t_in = _triangle_fill(hole, hole_area)
    if t_in >= 0.66:
        badness = max((1 - t_out) / 0.2, (1 - t_in) / 0.34, offset / 0.12)
        return Shape.TRIANGLE, 1.0 - 0.5 * badness
    return None


def _cross(
    b: _Blob, hull_pts: np.ndarray, hull_area: float, max_solidity: float = X_SOLIDITY
) -> tuple[Shape, float] | None:
    """Four arms around one centre (`hull_pts`: the outline's convex hull, of area `hull_area`), filling at most
    `max_solidity` of it (`DetectorConfig.x_solidity`)."""
    solidity = b.area / hull_area
    if not 0.18 <= solidity <= max_solidity:
        return None
    hull_idx = cv2.convexHull(b.outer, returnPoints=False)
    try:
        defects = cv2.convexityDefects(b.outer, hull_idx)
    except cv2.error:  # a self-touching contour
        return None
    if defects is None:
        return None
    scale = math.sqrt(hull_area)
    d = defects.reshape(-1, 4)
    deep = d[d[:, 3] / 256.0 >= 0.1 * scale]
    if len(deep) != 4:
        return None
    pts = b.outer[:, 0, :].astype(np.float64)
    far = pts[deep[:, 2]]
    centre = far.mean(axis=0)
    hull_c = _centroid(hull_pts)
    offset = float(np.hypot(*(centre - hull_c))) / scale
    spread = float(np.max(np.hypot(*(far - centre).T))) / scale
    if offset > 0.15 or spread > 0.3:
        return None
    # the four arms: contour runs between consecutive defect points, each with its farthest tip
    order = np.sort(deep[:, 2])
    arms = []
    for k in range(4):
        a, z = order[k], order[(k + 1) % 4]
        seg = pts[a : z + 1] if z > a else np.concatenate([pts[a:], pts[: z + 1]])
        arms.append(float(np.max(np.hypot(*(seg - centre).T))))
    arm_ratio = min(arms) / max(arms)
    if arm_ratio < 0.45:
        return None
    badness = max(offset / 0.15, spread / 0.3, (1 - arm_ratio) / 0.55)
    return Shape.X, 1.0 - 0.5 * badness


def _centroid(c: np.ndarray) -> np.ndarray:
    m = cv2.moments(c)
    if m["m00"] == 0:
        return c.reshape(-1, 2).mean(axis=0)
    return np.array([m["m10"] / m["m00"], m["m01"] / m["m00"]])


def _ellipse_residual(c: np.ndarray) -> float | None:
    """Mean |r - 1| of the contour points in the frame of the fitted ellipse (0 for an ellipse)."""
    if len(c) < 6:
        return None
    (cx, cy), (ma, mb), ang = cv2.fitEllipse(c)
    if ma <= 1 or mb <= 1:
        return None
    p = c.reshape(-1, 2).astype(np.float64) - (cx, cy)
    t = math.radians(ang)
    u = (p[:, 0] * math.cos(t) + p[:, 1] * math.sin(t)) / (ma / 2)
    v = (-p[:, 0] * math.sin(t) + p[:, 1] * math.cos(t)) / (mb / 2)
    return float(np.mean(np.abs(np.hypot(u, v) - 1.0)))


def _axis_ratio(c: np.ndarray) -> float:
    _, (ma, mb), _ = cv2.fitEllipse(c)
    return min(ma, mb) / max(ma, mb, 1e-9)


def _triangle_fill(c: np.ndarray, area: float) -> float:
    try:
        tri_area, _ = cv2.minEnclosingTriangle(c.astype(np.float32))
    except cv2.error:
        return 0.0
    return float(area / tri_area) if tri_area > 0 else 0.0


def _in_text_line(
    stats: np.ndarray,
    i: int,
    g: np.ndarray,
    labels: np.ndarray,
    paper_share: float = 0.0,
    turned: bool = False,
    whole: str = "",
    twin: float = 0.0,
) -> bool:
    """A letter inside a word: letter-sized neighbours in the same ink on its baseline or cap line -
    two of them, the nearest less than half a letter height away and the other within two; or one
    close neighbour of the very same height beside it. (Any one neighbour is not enough: the fingers
    holding a card come close to a mark; and the dark background at a card's corners is not ink.)
    `turned`: also look along the line to each letter-sized neighbour, for a word seen turned (a
    camera's roll, a sign hung askew); there two neighbours in line are needed, or one twin
    (`_line_of_letters`). `whole`: only components wholly inside the image count as neighbours on the
    turned lines ("turned") or on every line ("all"; `DetectorConfig.text_whole`). `twin`: on a turned line, a lone
    neighbour that far from the candidate's size is a twin too where it is printed on the candidate's paper in its ink
    (`DetectorConfig.text_twin`)."""
    rows = turned_rows = _around(stats, i)
    if whole:
        H, W = labels.shape[:2]
        sx, sy, sw, sh = (stats[rows, k] for k in range(4))
        turned_rows = rows[(sx > 0) & (sy > 0) & (sx + sw < W) & (sy + sh < H)]
        if whole == "all":
            rows = turned_rows
    letters = _Letters(g, labels, stats, i, paper_share)
    if len(rows) and _line_of_letters(letters, 0.0, rows):
        return True
    if not turned or not len(turned_rows):
        return False
    rows = turned_rows
    x, y, w, h, area = (int(v) for v in stats[i][:5])
    xs, ys, ws, hs, areas = (stats[rows, k] for k in range(5))
    dx = xs + ws / 2 - (x + w / 2)
    dy = ys + hs / 2 - (y + h / 2)
    dist = np.hypot(dx, dy)
    size = max(w, h)
    letter = (
        (np.maximum(ws, hs) >= 0.7 * size)
        & (np.maximum(ws, hs) <= 1.45 * size)
        & (areas >= 0.15 * area)
        & (dist >= 0.5 * size)
        & (dist <= 1.3 * size)
    )
    tried: list[float] = []
    for j in np.flatnonzero(letter)[:4]:
        angle = float(np.degrees(np.arctan2(dy[j], dx[j]))) % 180.0
        if all(abs(angle - a) > 3.0 for a in tried) and min(angle, 180.0 - angle) > 3.0:
            tried.append(angle)
            if _line_of_letters(letters, angle, rows, twin):
                return True
    return False


class _Letters:
    """What the text-line tests measure of candidate `i` and its neighbours that does not depend on the
    line tried (the baseline and up to four turned ones): the candidate's ink and paper levels, and
    each neighbour's mean grey and paper ring, each computed once, when first asked for."""

    def __init__(
        self, g: np.ndarray, labels: np.ndarray, stats: np.ndarray, i: int, paper_share: float
    ) -> None:
        self.g, self.labels, self.stats, self.i, self.paper_share = g, labels, stats, i, paper_share
        self._levels: tuple[float, float] | None = None
        self._means: dict[int, float] = {}
        self._rings: dict[int, float] = {}

    def levels(self) -> tuple[float, float]:
        """The candidate's mean grey (its ink) and the 90th percentile of its box (the paper)."""
        if self._levels is None:
            x, y, w, h = (int(v) for v in self.stats[self.i][:4])
            ink = _component_mean(self.g, self.labels, self.stats, self.i)
            self._levels = ink, _percentile(self.g[y : y + h, x : x + w], 90)
        return self._levels

    def mean(self, j: int) -> float:
        if j not in self._means:
            self._means[j] = _component_mean(self.g, self.labels, self.stats, j)
        return self._means[j]

    def ring_grey(self, j: int) -> float:
        """The median grey of a thin ring round neighbour `j` (`_ring`): the paper it is printed on."""
        x0, y0, ring = _ring(self.labels, self.stats, j)
        around = self.g[y0 : y0 + ring.shape[0], x0 : x0 + ring.shape[1]][ring > 0]
        return float(np.median(around)) if around.size else math.inf

    def paper_round(self, j: int) -> float:
        """`_paper_round` of neighbour `j`, cut half-way between the candidate's ink and paper."""
        if j not in self._rings:
            ink, paper = self.levels()
            self._rings[j] = _paper_round(self.g, self.labels, self.stats, j, (ink + paper) / 2)
        return self._rings[j]


def _percentile(g: np.ndarray, q: float) -> float:
    """`np.percentile(g, q)` of a uint8 image (its default, linear method), from the image's histogram
    (`_ranked`): the same value, bit for bit (tests/vision), without converting and partitioning every
    pixel."""
    n = g.size
    virtual = (n - 1) * (q / 100)  # numpy's index into the sorted pixels, and its rounding
    below = min(math.floor(virtual), n - 1)
    gamma = virtual - below
    low, high = _ranked(g, None, [below, min(below + 1, n - 1)])
    step = high - low  # numpy's interpolation, in its two forms
    return high - step * (1 - gamma) if gamma >= 0.5 else low + step * gamma


def _around(stats: np.ndarray, i: int) -> np.ndarray:
    """The components (rows of `stats`, in label order, without the background and `i` itself) whose
    centre lies within 3.5 x the size of `i` of its centre, in x and in y: every one the text-line
    tests could count as a neighbour (the baseline test's farthest is 3.25 sizes away in x, the turned
    test's 2.81 along its line), so they compute on these few rows instead of every component of the
    level: the same verdicts (tests/vision/test_exact_shortcuts.py)."""
    x, y, w, h = (int(v) for v in stats[i][:4])
    reach = 7 * max(w, h)  # in doubled coordinates, as the centres below
    dx = 2 * stats[:, 0] + stats[:, 2] - (2 * x + w)
    dy = 2 * stats[:, 1] + stats[:, 3] - (2 * y + h)
    near = (np.abs(dx) <= reach) & (np.abs(dy) <= reach)
    near[0] = near[i] = False
    return np.flatnonzero(near)


def _line_of_letters(letters: _Letters, angle: float, rows: np.ndarray, twin: float = 0.0) -> bool:
    """`_in_text_line` along a line turned by `angle` degrees (0: the horizontal baseline test), over the
    neighbours `rows` (`_around`) of the candidate `letters` measures; on a turned line a lone neighbour within
    `twin` of its size, on its paper in its ink, is a twin as well (`DetectorConfig.text_twin`)."""
    stats = letters.stats
    x, y, w, h, area = (int(v) for v in stats[letters.i][:5])
    xs, ys, ws, hs, areas = (stats[rows, k] for k in range(5))
    if angle == 0.0:
        cy = y + h / 2
        gap = np.maximum(xs - (x + w), x - (xs + ws))  # horizontal gap between the boxes (<0: overlap)
        line = (np.abs(ys + hs / 2 - cy) <= 0.25 * h) & (
            (np.abs(ys + hs - (y + h)) <= 0.12 * h) | (np.abs(ys - y) <= 0.12 * h)  # baseline or cap line
        )
        twin_line = (np.abs(ys - y) <= 0.1 * h) & (np.abs(ys + hs - (y + h)) <= 0.1 * h)
        paper_twin = None  # the looser twin is for turned lines only
        beside, close = (gap >= 0) & (gap <= 2.0 * h), gap <= 0.5 * h
    else:
        # a turned letter's upright box is no guide to where the letter ends along the line, so the
        # centres' distance along it is judged instead: a letter's width plus the gap, 0.5 to 1.3 box
        # sizes for the near neighbour and up to 2.8 for the other (the horizontal test's gaps of 0 to
        # 2 heights, from a bigger box)
        t = np.radians(angle)
        dx = xs + ws / 2 - (x + w / 2)
        dy = ys + hs / 2 - (y + h / 2)
        along = np.abs(np.cos(t) * dx + np.sin(t) * dy)
        across = np.abs(-np.sin(t) * dx + np.cos(t) * dy)
        size = max(w, h)
        line = across <= 0.15 * h
        # one neighbour is enough only when it is the candidate's twin: centred on the line and its upright
        # box's longest side within a tenth of the candidate's (a two-letter word, NO or OK, seen turned a
        # little; within a fifth, seed 99 lost 7 more tuning marks)
        twin_line = (across <= 0.1 * h) & (np.abs(np.maximum(ws, hs) - size) <= 0.1 * size)
        # `twin`: a lone neighbour further from its size, if on the candidate's paper in its ink (below)
        paper_twin = (
            (across <= 0.1 * h) & (np.abs(np.maximum(ws, hs) - size) <= twin * size) & ~twin_line if twin > 0 else None
        )
        beside, close = (along >= 0.5 * size) & (along <= 2.8 * size), along <= 1.3 * size
    similar = (
        (hs >= 0.7 * h)
        & (hs <= 1.45 * h)
        & line
        & (ws >= 0.1 * h)
        & (ws <= 1.5 * h)
        & (areas >= 0.15 * area)
        & beside
    )
    if not (similar & close).any():
        return False
    # keep only neighbours written in the same ink as the candidate (and, with `paper_share`, printed
    # on paper: light all round them, unlike the dark background beyond a card's edge)
    ink, paper = letters.levels()
    tolerance = max(8.0, 0.25 * (paper - ink))
    for k in np.flatnonzero(similar):
        j = int(rows[k])
        if abs(letters.mean(j) - ink) > tolerance or (
            letters.paper_share > 0 and letters.paper_round(j) < letters.paper_share
        ):
            similar[k] = False
    near = similar & close
    if not near.any():
        return False
    if int(similar.sum()) >= 2:
        return True
    if (near & twin_line).any():
        return True
    if paper_twin is None or paper - ink < TWIN_CONTRAST or max(w, h) < TWIN_SIZE:
        return False
    return any(
        abs(letters.mean(j) - ink) <= TWIN_INK * (paper - ink)
        and abs(letters.ring_grey(j) - paper) <= TWIN_PAPER * (paper - ink)
        for j in (int(rows[k]) for k in np.flatnonzero(near & paper_twin))
    )


def _paper_round(
    g: np.ndarray, labels: np.ndarray, stats: np.ndarray, j: int, cut: float, within: np.ndarray | None = None
) -> float:
    """The share of a thin ring just outside component `j` that is lighter than `cut` (and, with `within`, a mask
    over `g`, inside it)."""
    x0, y0, ring = _ring(labels, stats, j)
    n = cv2.countNonZero(ring)
    if n == 0:
        return 0.0
    y1, x1 = y0 + ring.shape[0], x0 + ring.shape[1]
    light = g[y0:y1, x0:x1][ring > 0] > cut
    if within is not None:
        light &= within[y0:y1, x0:x1][ring > 0] > 0
    return float(np.count_nonzero(light)) / n


def _ring(labels: np.ndarray, stats: np.ndarray, j: int) -> tuple[int, int, np.ndarray]:
    """A thin ring just outside component `j` (2 to 3 pixels out): its region's corner (x0, y0) in `labels` and the
    ring's mask over that region."""
    x, y, w, h = (int(v) for v in stats[j][:4])
    x0, y0 = max(0, x - 4), max(0, y - 4)
    x1, y1 = min(labels.shape[1], x + w + 4), min(labels.shape[0], y + h + 4)
    own = cv2.inRange(labels[y0:y1, x0:x1], j, j)
    return x0, y0, cv2.subtract(cv2.dilate(own, np.ones((7, 7), np.uint8)), cv2.dilate(own, np.ones((3, 3), np.uint8)))


def _component_mean(g: np.ndarray, labels: np.ndarray, stats: np.ndarray, i: int) -> float:
    x, y, w, h = (int(v) for v in stats[i][:4])
    mask = cv2.inRange(labels[y : y + h, x : x + w], i, i)
    return float(cv2.mean(g[y : y + h, x : x + w], mask=mask)[0])


def _up(box: Box | np.ndarray, f: int) -> Box:
    """A box (x, y, w, h; or a row of connected-component stats) at a pyramid level of downscale `f`,
    in the input's pixels."""
    x, y, w, h = (int(v) * f for v in box[:4])
    return (x, y, w, h)


def _down(box: Box, f: int) -> Box:
    """A box in the input's pixels at a pyramid level of downscale `f`."""
    x, y, w, h = box
    return (x // f, y // f, max(1, w // f), max(1, h // f))


def _merge(dets: list[Detection], overlap: float) -> list[Detection]:
    """Greedy: best confidence first; drop any detection mostly overlapping one already kept."""
    kept: list[Detection] = []
    for d in sorted(dets, key=lambda d: -d.confidence):
        if all(box_overlap(d.box, k.box) <= overlap for k in kept):
            kept.append(d)
    return kept


def box_overlap(a: Box, b: Box) -> float:
    ix = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    smaller = min(a[2] * a[3], b[2] * b[3])
    return ix * iy / smaller if smaller > 0 else 0.0
