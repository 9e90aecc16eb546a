"""The floor held over the robot's own voice (`SegmenterConfig.floor_hold`, `floor_hold_after`; on by default since
round voice51c, held throughout did not pass rounds voice51 and 51b): what the echo canceller leaves of the robot's
voice does not feed the segmenter's noise floor, so a word said just after the robot's sentence is judged against the
room's floor from before it."""

from __future__ import annotations

import numpy as np
import pytest

from bench.voice_own import _cancelled
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.echo import FILTER_S, LEAD_S, EchoCanceller, Played
from services.voice.engine import EngineError
from services.voice.segmenter import Segment, Segmenter, SegmenterConfig
from services.voice.service import VoiceSettings
from tests.voice.streams import STEP

needs_espeak = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
HOLD = SegmenterConfig(floor_hold=True, floor_hold_after=False)
AFTER = SegmenterConfig(floor_hold=True, floor_hold_after=True)
UNHELD = SegmenterConfig(floor_hold=False)


def _word() -> np.ndarray:
    speech = np.frombuffer(read_wav(synth.speech_clip("stop", "en-us", 150).path), "<i2") / 32768.0
    loud = np.flatnonzero(np.abs(speech) > 0.02 * np.abs(speech).max())
    return speech[loud[0] : loud[-1] + 1] * 0.1 / np.abs(speech).max()  # -20 dBFS peak


def _after_residue(residue_dbfs: float | None) -> tuple[bytes, int, int]:
    """1 s of a quiet room's hiss, 1.5 s of what a canceller left of the robot's voice (white noise at `residue_dbfs`
    RMS over the hiss; None: none), 0.15 s of hiss, "stop", 1 s of hiss: the stream, and where the residue begins and
    ends (bytes)."""
    rng = np.random.default_rng(3)
    word = _word()
    residue = np.zeros(int(1.5 * SAMPLE_RATE))
    if residue_dbfs is not None:
        residue = rng.normal(0.0, 10 ** (residue_dbfs / 20), residue.size)
    x = np.concatenate([np.zeros(SAMPLE_RATE), residue, np.zeros(int(0.15 * SAMPLE_RATE)), word,
                        np.zeros(SAMPLE_RATE)])
    x += rng.normal(0.0, 3e-4, x.size)  # -70 dBFS
    return to_pcm(x), 2 * SAMPLE_RATE, 2 * (SAMPLE_RATE + residue.size)


def _heard(pcm: bytes, robot: tuple[int, int], config: SegmenterConfig) -> list[tuple[float, Segment]]:
    """(emitted at, segment) with the chunks that overlap `robot` (bytes) fed as the robot's voice."""
    seg = Segmenter(config)
    out = []
    for k in range(0, len(pcm), STEP):
        near = k < robot[1] and k + STEP > robot[0]
        out += [((k + STEP) / 2 / SAMPLE_RATE, s) for s in seg.feed(pcm[k : k + STEP], robot=near)]
    return out


@needs_espeak
def test_a_word_after_the_robots_voice_is_judged_against_the_floor_from_before_it() -> None:
    """Over the residue the floor rises 25 dB unheld and the word is not clear, so the whole end window is waited for;
    held, the word is as far over the floor as with no residue, and ends at the clear window (60 ms sooner)."""
    alone_pcm, _, _ = _after_residue(None)
    pcm, lo, hi = _after_residue(-45.0)
    [(_, alone)] = _heard(alone_pcm, (lo, hi), HOLD)
    [(t_held, held)] = _heard(pcm, (lo, hi), HOLD)
    [(t_unheld, unheld)] = _heard(pcm, (lo, hi), UNHELD)
    assert alone.snr_db is not None and held.snr_db is not None and unheld.snr_db is not None
    assert held.snr_db == pytest.approx(alone.snr_db, abs=1.0) and held.snr_db >= SegmenterConfig.clear_snr_db
    assert unheld.snr_db < held.snr_db - 15.0 and unheld.snr_db < SegmenterConfig.clear_snr_db
    assert t_unheld - t_held >= 0.06 - 1e-6
    # not said to be the robot's voice, the residue feeds the floor whatever the setting
    [(_, told_nothing)] = _heard(pcm, (0, 0), HOLD)
    assert told_nothing.snr_db == pytest.approx(unheld.snr_db, abs=1e-6)


@needs_espeak
def test_held_only_after_the_robots_voice_a_word_within_it_is_judged_as_without_the_hold() -> None:
    """`floor_hold_after`: a word after the residue is judged against the held floor, as with the hold throughout; the
    same word while the robot's voice is still said to lie in the stream is judged against the floor with the residue
    in it, and cut, as without the hold (where the hold throughout judges it against the held floor)."""
    pcm, lo, hi = _after_residue(-45.0)
    [(t_held, held)] = _heard(pcm, (lo, hi), HOLD)
    [(t_after, after)] = _heard(pcm, (lo, hi), AFTER)
    assert (t_after, after.snr_db, after.start_s, after.end_s) == (t_held, held.snr_db, held.start_s, held.end_s)
    near = (lo, len(pcm))  # the robot's voice said to lie in the stream to its end, over the word too
    [(t_unheld, unheld)] = _heard(pcm, near, UNHELD)
    [(t_within, within)] = _heard(pcm, near, AFTER)
    [(t_held_within, held_within)] = _heard(pcm, near, HOLD)
    assert (t_within, within.snr_db, within.end_s) == (t_unheld, unheld.snr_db, unheld.end_s)
    assert held_within.snr_db is not None and unheld.snr_db is not None
    assert held_within.snr_db > unheld.snr_db + 15.0 and t_held_within < t_unheld


@needs_espeak
def test_the_canceller_says_where_the_robots_voice_lies() -> None:
    """`robot_near`: False before the robot's sentence may begin, True while it plays and for the filter's reach after
    it, False again once that has passed; and `bench.voice_own._cancelled` says so per sample, as many as it passes."""
    pytest.importorskip("pyaec")  # the canceller's library (Linux x86_64 wheels); the segmenter's tests need none
    voice = synth.speak("Sorry, I cannot do it.", "en-us", 175) * 0.5
    x = np.random.default_rng(1).normal(0.0, 1e-3, 5 * SAMPLE_RATE)
    start = int(1.07 * SAMPLE_RATE)
    x[start : start + voice.size] += 0.3 * voice
    played = Played()
    played.add(101.0, voice)
    canceller = EchoCanceller(played)
    pcm, block = to_pcm(x), 2 * int(0.03 * SAMPLE_RATE)
    near = []
    for k in range(0, len(pcm), block):
        out = canceller(pcm[k : k + block], 100.0 + k / 2 / SAMPLE_RATE)
        near += [canceller.robot_near] * (len(out) // 2)
    flags = np.array(near)
    placed = start - int(LEAD_S * SAMPLE_RATE)
    assert not flags[: int(0.8 * SAMPLE_RATE)].any()  # the search begins 0.1 s before the state's 1.0 s
    assert flags[placed : placed + voice.size].all()
    assert flags[placed + voice.size : placed + voice.size + int(FILTER_S * SAMPLE_RATE) - 480].all()
    assert not flags[placed + voice.size + int(FILTER_S * SAMPLE_RATE) + 480 :].any()
    z, mask = _cancelled([(101.0, voice)], {}, pcm, block, 100.0)
    assert z.size == mask.size == x.size and np.array_equal(mask[: flags.size], flags)


def test_the_setting() -> None:
    assert SegmenterConfig().floor_hold is True  # round voice51c
    assert VoiceSettings().segmenter().floor_hold is True
    assert VoiceSettings(floor_hold="off").segmenter().floor_hold is False
    assert VoiceSettings(floor_hold="on").segmenter().floor_hold is True
    assert VoiceSettings(floor_hold="on").segmenter().floor_hold_after is False  # held throughout
    after = VoiceSettings(floor_hold="after").segmenter()
    assert after.floor_hold is True and after.floor_hold_after is True
    assert SegmenterConfig().floor_hold_after is True
    with pytest.raises(EngineError, match="HRI_VOICE_FLOOR_HOLD"):
        VoiceSettings(floor_hold="held").segmenter()
