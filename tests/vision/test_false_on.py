"""What a false mark lies on: the held-out generator records what it drew in each frame (`heldout.Drawn`, stop
119), the tuning generator when asked the pixels each thing changed (`synthetic.Painted`, stop 120), neither drawing a
random number more, and `bench/vision_bench.py` charges each false mark to the thing under it (`lies_on`,
`lies_on_painted`): the frame's true mark, the last thing drawn there, or the background."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import typer
from typer.testing import CliRunner

from bench import vision_bench
from schemas.messages import Shape
from services.vision.heldout import HELDOUT_BACKGROUNDS, Drawn, HeldOutGenerator
from services.vision.synthetic import DISTRACTORS, Painted, SceneGenerator, Variation

CLUTTER = {"words", "sign", "square", "disc", "triangle", "face", "cable", "texture"}
HELD = {"mark card", "blank card", "decoy disc", "decoy square", "decoy outline square", "decoy word"}
TUNING_CLUTTER = {*DISTRACTORS, "decoy outline square", "decoy disc", "decoy filled square", "decoy word"} - {"card"}


def test_each_frame_records_its_background_its_clutter_and_the_card_held_up_last() -> None:
    gen = HeldOutGenerator(seed=4)
    kinds: set[str] = set()
    for i in range(24):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE, None)[i % 4]
        img, label = gen.frame(shape)
        assert gen.background in (*HELDOUT_BACKGROUNDS, "room")
        clutter = [d for d in gen.drawn if d.kind in CLUTTER]
        assert 1 <= len(clutter) <= 6 and all(d.kind in CLUTTER | HELD for d in gen.drawn)
        kinds |= {d.kind for d in gen.drawn}
        for d in gen.drawn:
            x, y, w, h = d.box
            assert w > 0 and h > 0 and x < img.shape[1] and y < img.shape[0] and x + w > 0 and y + h > 0
        if label is not None:  # the mark's card is drawn last, and holds the mark
            card = gen.drawn[-1]
            assert card.kind == "mark card"
            cx, cy = label.box[0] + label.box[2] / 2, label.box[1] + label.box[3] / 2
            assert card.box[0] <= cx <= card.box[0] + card.box[2] and card.box[1] <= cy <= card.box[1] + card.box[3]
        else:
            assert "mark card" not in {d.kind for d in gen.drawn}
    assert {"words", "cable", "mark card"} <= kinds


def test_the_record_draws_no_random_number_a_seed_draws_the_same_frames() -> None:
    a, b = HeldOutGenerator(seed=9), HeldOutGenerator(seed=9)
    for shape in (Shape.X, None, Shape.O):
        first, _ = a.frame(shape)
        b.drawn = [Drawn("words", (0, 0, 5, 5))] * 50  # a record left from before changes nothing drawn
        second, _ = b.frame(shape)
        assert np.array_equal(first, second)


def test_a_false_mark_is_charged_to_the_mark_the_thing_on_top_under_it_or_the_background() -> None:
    curve = np.array([[0.0, 300.0], [640.0, 300.0]])
    gen = SimpleNamespace(
        background="cat",
        drawn=[
            Drawn("words", (100, 100, 80, 30)),
            Drawn("decoy word", (90, 90, 60, 60)),  # held up over the words: on top
            Drawn("cable", (0, 300, 641, 1), curve, 8.0),
        ],
    )
    assert vision_bench.lies_on(gen, (400, 50, 40, 40), (405, 55, 30, 30)) == "the mark itself"
    assert vision_bench.lies_on(gen, (100, 100, 20, 20), None) == "decoy word"
    assert vision_bench.lies_on(gen, (160, 100, 16, 16), None) == "words"
    assert vision_bench.lies_on(gen, (300, 290, 20, 20), None) == "cable"  # its centre 4 px beside the curve
    assert vision_bench.lies_on(gen, (300, 240, 20, 20), None) == "background: cat"


def test_the_bench_tells_held_out_false_marks_by_what_they_lie_on_and_only_there() -> None:
    held = _run("--split", "heldout", "--frames", "200", "--seed", "5")  # 5 false marks on this seed
    on = held["false_marks_on"]
    assert on and all(set(c) == {"X", "O", "TRIANGLE", "mark_free_frames"} for c in on.values())
    for shape in ("X", "O", "TRIANGLE"):
        assert sum(c[shape] for c in on.values()) == held["per_class"][shape]["false"]
    with_one = round(held["false_mark_rate"] * held["mark_free_frames"])
    assert max(c["mark_free_frames"] for c in on.values()) <= with_one <= sum(c["mark_free_frames"] for c in on.values())
    assert "false_marks_on" not in _run("--split", "blind", "--frames", "8", "--seed", "5")


def test_a_recording_tuning_generator_draws_the_same_frames_and_records_what_it_drew() -> None:
    """Stop 120: the tuning generator records the pixels each clutter and the held card changed (`synthetic.Painted`)
    when asked (`record`), and draws no random number more for it."""
    plain, recording = SceneGenerator(seed=11), SceneGenerator(seed=11)
    recording.record = True
    kinds: set[str] = set()
    for i in range(24):
        shape = (Shape.X, Shape.O, Shape.TRIANGLE, None)[i % 4]
        first, _ = plain.frame(shape)
        img, labels = recording.frame(shape)
        assert np.array_equal(first, img)
        assert not plain.painted and plain.card is None
        assert recording.background in (*recording.bank_names, "procedural")
        lo, hi = Variation().distractors
        assert lo <= len(recording.painted) <= hi
        for painted in recording.painted:
            assert painted.kind in TUNING_CLUTTER and painted.mask.shape == img.shape[:2] and painted.mask.dtype == bool
        kinds |= {p.kind for p in recording.painted}
        if labels:  # the held card holds the mark's middle
            x, y, w, h = labels[0].box
            assert recording.card is not None and recording.card.mask[y + h // 2, x + w // 2]
        else:
            assert recording.card is None
    assert {"text", "cable"} <= kinds


def test_a_tuning_false_mark_is_charged_to_the_card_the_newest_clutter_under_it_or_the_background() -> None:
    def mask(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        m = np.zeros((480, 640), bool)
        m[y0:y1, x0:x1] = True
        return m

    gen = SimpleNamespace(background="coins", card=Painted("mark card", mask(400, 40, 480, 120)),
                          painted=[Painted("text", mask(100, 100, 200, 130)), Painted("cable", mask(0, 298, 640, 302)),
                                   Painted("decoy word", mask(90, 90, 150, 150))])
    assert vision_bench.lies_on_painted(gen, (420, 60, 30, 30), (425, 65, 25, 25)) == "the mark itself"
    assert vision_bench.lies_on_painted(gen, (400, 40, 20, 20), None) == "mark card"
    assert vision_bench.lies_on_painted(gen, (100, 100, 20, 20), None) == "decoy word"  # drawn last, on top
    assert vision_bench.lies_on_painted(gen, (170, 100, 16, 16), None) == "text"
    assert vision_bench.lies_on_painted(gen, (300, 285, 20, 20), None) == "cable"  # within a quarter of its size
    assert vision_bench.lies_on_painted(gen, (300, 240, 20, 20), None) == "background: coins"


def test_the_bench_tells_tuning_false_marks_by_what_they_lie_on_but_not_through_a_lens() -> None:
    tuning = _run("--split", "tuning", "--frames", "100", "--seed", "11")  # 2 false marks on this seed
    on = tuning["false_marks_on"]
    assert on and all(kind in TUNING_CLUTTER | {"mark card", "the mark itself"} or kind.startswith("background: ")
                      for kind in on), on
    for shape in ("X", "O", "TRIANGLE"):
        assert sum(c[shape] for c in on.values()) == tuning["per_class"][shape]["false"]
    assert "false_marks_on" not in _run("--split", "tuning", "--frames", "8", "--seed", "5", "--lens", "0.2")


def _run(*args: str) -> dict:
    app = typer.Typer()
    app.command()(vision_bench.main)
    return json.loads(CliRunner().invoke(app, [*args, "--json"]).stdout)
