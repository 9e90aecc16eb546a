"""k-of-n debounce: confirmation delay, robustness to single noisy frames, release delay."""

from __future__ import annotations

import pytest

from schemas.messages import Shape
from services.vision.debounce import Confirmation, DebounceConfig, Debouncer
from services.vision.detector import Detection

X = Detection(Shape.X, 0.9, (10, 10, 40, 40))
O_ = Detection(Shape.O, 0.8, (100, 10, 40, 40))


def _run(deb: Debouncer, frames: list[list[Detection]]) -> list[set[Shape]]:
    return [{d.shape for d in deb.update(f)} for f in frames]


def test_confirmed_on_the_kth_frame_and_released_after_n_minus_k_plus_1_misses() -> None:
    deb = Debouncer(DebounceConfig(3, 5))
    out = _run(deb, [[X], [X], [X], [X], [], [], [], []])
    assert out == [set(), set(), {Shape.X}, {Shape.X}, {Shape.X}, {Shape.X}, set(), set()]


def test_single_noisy_frame_neither_raises_nor_drops_a_mark() -> None:
    deb = Debouncer(DebounceConfig(3, 5))
    assert _run(deb, [[O_], [], [], [O_], [], []]) == [set()] * 6  # flicker never confirms
    deb.reset()
    out = _run(deb, [[X], [X], [X], [], [X], [X]])
    assert all(Shape.X in s for s in out[2:])  # one missed frame keeps it


def test_shapes_are_independent_and_box_is_the_latest() -> None:
    one = DebounceConfig(2, 3)
    deb = Debouncer(Confirmation(danger=one, safe=one, clear_of_danger=False))
    moved = Detection(Shape.X, 0.7, (20, 20, 40, 40))
    deb.update([X, O_])
    out = deb.update([moved, O_])
    assert {d.shape for d in out} == {Shape.X, Shape.O}
    x = next(d for d in out if d.shape is Shape.X)
    assert x.box == moved.box
    assert x.confidence == pytest.approx(0.8)


def test_one_of_one_passes_everything_through() -> None:
    deb = Debouncer(DebounceConfig(1, 1))
    assert _run(deb, [[X], [], [O_]]) == [{Shape.X}, set(), {Shape.O}]


@pytest.mark.parametrize("text", ["3", "a/b", "0/5", "6/5", "3/5/7", ""])
def test_bad_debounce_specs_are_rejected(text: str) -> None:
    with pytest.raises(ValueError):
        DebounceConfig.parse(text)


def test_parse_round_trips() -> None:
    assert str(DebounceConfig.parse("2/4")) == "2/4"


T = Detection(Shape.TRIANGLE, 0.7, (200, 10, 40, 40))


def test_danger_acts_on_the_first_frame_and_is_held_two_more() -> None:
    deb = Debouncer()  # danger 1/3, safe 3/4
    assert _run(deb, [[X], [], [], [], [T], [], [T]]) == [
        {Shape.X},
        {Shape.X},
        {Shape.X},
        set(),
        {Shape.TRIANGLE},
        {Shape.TRIANGLE},
        {Shape.TRIANGLE},
    ]


def test_safe_mark_needs_three_of_four_frames() -> None:
    deb = Debouncer()
    assert _run(deb, [[O_], [], [O_], [], [O_]]) == [set()] * 5  # every other frame never clears
    deb.reset()
    out = _run(deb, [[O_], [O_], [O_], [O_], [], [], []])
    assert out == [set(), set(), {Shape.O}, {Shape.O}, {Shape.O}, set(), set()]


def test_confirmation_windows_are_per_kind() -> None:
    conf = Confirmation(danger=DebounceConfig(2, 2), safe=DebounceConfig(1, 1), clear_of_danger=False)
    deb = Debouncer(conf)
    assert _run(deb, [[X, O_], [X], []]) == [{Shape.O}, {Shape.X}, set()]
    assert str(conf) == "danger 2/2, safe 1/1"


def test_an_o_is_not_confirmed_in_a_window_with_a_danger_mark() -> None:
    """Round vision31: an O beside an X that flickers never lifts the danger in a frame the X is missing from."""
    deb = Debouncer()  # danger 1/3, safe 3/4
    frames = [[X, O_], [O_], [X, O_], [O_], [O_], [O_], [O_]]
    # the X is held 2 frames after it was seen; the O waits until no X is in its own last 4 frames
    assert _run(deb, frames) == [{Shape.X}, {Shape.X}, {Shape.X}, {Shape.X}, {Shape.X}, set(), {Shape.O}]
    before = Debouncer(Confirmation(clear_of_danger=False))
    assert _run(before, frames)[3] == {Shape.X, Shape.O}  # as it was: the O confirmed beside the X
    assert _run(before, [[X], [O_], [O_], [O_]])[3] == {Shape.O}  # the X missing: the danger would be lifted
    for danger in (X, T):  # a danger card swapped for an O: the O one frame later than without the rule
        deb.reset()
        assert _run(deb, [[danger], [O_], [O_], [O_], [O_]])[2:] == [{danger.shape}, set(), {Shape.O}]
