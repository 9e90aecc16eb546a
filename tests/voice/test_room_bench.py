"""bench/voice_room.py's rooms: every place fits the room, each response starts with its direct sound at the gain the
distance gives, a farther person is heard with more of the room than of the voice, and the room's reverberation time
is the one drawn (pyroomacoustics' image-source model, measured back from its response)."""

from __future__ import annotations

import numpy as np
import pytest

from bench.voice_room import (
    DIRECT_AT,
    MIC_HEIGHTS_M,
    WALL_GAP_M,
    Speaker,
    direct_to_reverberant_db,
    draw_room,
    free_field,
    responses,
    ringing_s,
    rt60_range,
)
from bench.voice_walking import LEAD_S, TAIL_S
from services.voice.audio import SAMPLE_RATE


def test_every_place_is_in_the_room_at_its_distance_from_the_robot() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        room = draw_room(rng, [1.0, 2.0, 4.0], (0.3, 0.8))
        assert room.mic[2] in MIC_HEIGHTS_M and 0.3 <= room.rt60 <= 0.8
        for place in (room.mic, *room.mouths):
            assert all(WALL_GAP_M <= place[i] <= room.size[i] - WALL_GAP_M for i in (0, 1))
        across = [float(np.hypot(m[0] - room.mic[0], m[1] - room.mic[1])) for m in room.mouths]
        assert across == pytest.approx([1.0, 2.0, 4.0])


def test_a_room_too_small_for_the_distance_is_refused() -> None:
    with pytest.raises(ValueError, match="no room"):
        draw_room(np.random.default_rng(0), [12.0], (0.3, 0.8))


def test_the_response_starts_with_the_direct_sound_and_the_far_person_hears_more_room() -> None:
    room = draw_room(np.random.default_rng(11), [1.0, 2.0, 4.0], (0.4, 0.4))
    echoing, free = responses(room), free_field(room)
    for h, f in zip(echoing, free, strict=True):
        assert int(np.argmax(np.abs(h[: 2 * DIRECT_AT]))) == DIRECT_AT == int(np.argmax(f))
        # the fractional-delay filter spreads the direct sound over a few samples, at most the free field's gain
        assert 0.5 * f[DIRECT_AT] < abs(h[DIRECT_AT]) <= 1.02 * f[DIRECT_AT]
    drr = [direct_to_reverberant_db(h) for h in echoing]
    assert drr[0] > drr[1] > drr[2]
    assert drr[2] < -3.0  # 4 m is past an ordinary room's critical distance


def test_the_room_rings_for_at_least_the_time_drawn_and_longer_for_a_longer_one() -> None:
    """Sabine's formula sets the walls' absorption; an image-source shoebox rings a little longer than it says
    (the bench reports the measured time beside the drawn one)."""
    for seed in range(3):
        times = []
        for rt60 in (0.3, 0.5, 0.7):
            (h,) = responses(draw_room(np.random.default_rng(seed), [2.0], (rt60, rt60)))
            times.append(ringing_s(h))
            assert 0.85 * rt60 <= times[-1] <= 2.0 * rt60
        assert times == sorted(times)


def test_the_speaker_puts_each_clip_through_its_own_response_in_the_quiet_room() -> None:
    speech = np.sin(np.linspace(0, 400 * np.pi, SAMPLE_RATE // 2))
    near, far = np.zeros(DIRECT_AT + 1), np.zeros(DIRECT_AT + 1)
    near[DIRECT_AT], far[DIRECT_AT] = 1.0, 0.5
    speaker = Speaker([near, far], peak_db=-20.0, floor_db=-90.0, mic_rate=None)
    rng = np.random.default_rng(0)
    first, second = speaker(speech, rng), speaker(speech, rng)
    assert first.size == second.size == int(LEAD_S * SAMPLE_RATE) + speech.size + DIRECT_AT + int(TAIL_S * SAMPLE_RATE)
    assert 20 * np.log10(np.max(np.abs(first))) == pytest.approx(-20.0, abs=0.1)
    assert 20 * np.log10(np.max(np.abs(second)) / np.max(np.abs(first))) == pytest.approx(-6.02, abs=0.1)
    with pytest.raises(StopIteration):  # one response per clip: a third clip is a mistake in the caller
        speaker(speech, rng)


@pytest.mark.parametrize("raw", ["0.6,0.3", "0.3", "a,b", "0.01,0.2", "0.2,0.3,0.4"])
def test_a_bad_reverberation_range_is_refused(raw: str) -> None:
    with pytest.raises(ValueError, match="--rt60"):
        rt60_range(raw)
    assert rt60_range("0.25,0.6") == (0.25, 0.6)
