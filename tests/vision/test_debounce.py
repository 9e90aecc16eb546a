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
    before = Debouncer(Confirmation(clear_of_danger=False, new_safe_only=False))
    assert _run(before, frames)[3] == {Shape.X, Shape.O}  # as it was: the O confirmed beside the X
    assert _run(before, [[X], [O_], [O_], [O_]])[3] == {Shape.O}  # the X missing: the danger would be lifted
    for danger in (X, T):  # a danger card swapped for an O: the O one frame later than without the rule
        deb.reset()
        assert _run(deb, [[danger], [O_], [O_], [O_], [O_]])[2:] == [{danger.shape}, set(), {Shape.O}]


def _moved(d: Detection, dx: int, dy: int = 0) -> Detection:
    x, y, w, h = d.box
    return Detection(d.shape, d.confidence, (x + dx, y + dy, w, h))


def test_an_o_confirmed_before_the_danger_does_not_lift_it_while_it_stays() -> None:
    """Round vision32 (held-out clip 390 of seed 3141 with a hand): a clutter O confirmed before a triangle card
    came stays in view, the triangle drifts out of view; without the rule the O lifts the danger once the
    triangle has been missing for the O's window."""
    frames = [[O_]] * 4 + [[T, O_]] * 3 + [[O_]] * 10
    before = _run(Debouncer(Confirmation(new_safe_only=False)), frames)
    assert before[3] == {Shape.O} and before[4] == {Shape.TRIANGLE} and Shape.O in before[-1]  # lifted
    now = _run(Debouncer(), frames)
    assert now[3] == {Shape.O} and now[4] == {Shape.TRIANGLE}
    assert all(Shape.O not in out for out in now[4:])  # the O that was there all along never lifts it


def test_a_stale_o_follows_its_box_and_is_forgotten_once_out_of_view() -> None:
    deb = Debouncer()
    _run(deb, [[O_]] * 3 + [[X, O_]])  # O confirmed, then an X: the O is stale
    drifting = [[_moved(O_, 8 * i, 3 * i)] for i in range(1, 8)]  # the O moves 8 px a frame, the X is gone
    assert all(Shape.O not in out for out in _run(deb, drifting))  # (the X is held two frames)
    assert _run(deb, [[]] * 4) == [set()] * 4  # out of view for the O's window of 4 frames: forgotten
    assert _run(deb, [[O_]] * 3)[-1] == {Shape.O}  # shown anew, it says safe again


def test_an_o_shown_anew_lifts_the_danger_beside_a_stale_one() -> None:
    """Only the O that was there before the danger is left out: another O, or an O that was never confirmed
    before the danger (a card raised while the X is still up), counts."""
    elsewhere = Detection(Shape.O, 0.85, (300, 200, 50, 50))
    deb = Debouncer()
    _run(deb, [[O_]] * 3 + [[X, O_]])
    assert _run(deb, [[O_, elsewhere]] * 6)[-1] == {Shape.O}
    raised = Debouncer()
    assert _run(raised, [[X], [X, O_], [X, O_], [O_], [O_], [O_], [O_]])[-1] == {Shape.O}
    raised.reset()
    _run(raised, [[O_]] * 3 + [[X, O_]])
    raised.reset()  # a reset forgets the stale O too
    assert _run(raised, [[O_]] * 3)[-1] == {Shape.O}


def test_a_stale_o_is_not_forgotten_in_frames_that_report_a_danger_mark() -> None:
    """Round vision33 (held-out clip 390 of seed 3141 again, with a rolling shutter or automatic exposure alone): the
    detector reports only the marks up to a frame's first danger mark, so four triangle frames without the O aged the
    stale O out, and the same O lifted the danger once the triangle drifted out of view."""
    frames = [[O_]] * 4 + [[T]] * 4 + [[T, O_]] + [[O_]] * 8
    aged = _run(Debouncer(Confirmation(stale_held_by_danger=False)), frames)
    assert aged[3] == {Shape.O} and Shape.O in aged[-1]  # lifted by the O that was there all along
    held = _run(Debouncer(), frames)  # the service's, since round vision33
    assert held[3] == {Shape.O} and held[4] == {Shape.TRIANGLE}
    assert all(Shape.O not in out for out in held[4:])
    again = Debouncer(Confirmation(stale_held_by_danger=True))  # out of view for 4 frames without a danger: forgotten
    assert _run(again, frames[:9] + [[]] * 4 + [[O_]] * 3)[-1] == {Shape.O}
