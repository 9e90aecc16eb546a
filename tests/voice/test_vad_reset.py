"""Silero VAD's state over a long stream (`SegmenterConfig.vad_reset_s`, stop 91): it drifts in a quiet room, and a
word's end is then found late; the state starting again, warmed on the quiet it just heard, finds it as a new
stream's would."""

from __future__ import annotations

import numpy as np
import pytest

from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.engine import EngineError
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.service import VoiceSettings
from services.voice.vad import FRAME_SAMPLES, SileroEndpointer

QUIET = b"\0" * FRAME_SAMPLES * 2


class Model:
    """A VAD model that answers as told and records what it was asked."""

    def __init__(self) -> None:
        self.p = 0.0
        self.heard: list[tuple[bytes, float]] = []
        self.resets = 0

    def __call__(self, frame: bytes, gain: float = 1.0) -> float:
        self.heard.append((frame, gain))
        return self.p

    def reset(self) -> None:
        self.resets += 1
        self.heard.clear()


def _frame(k: int) -> bytes:
    return np.full(FRAME_SAMPLES, k, dtype="<i2").tobytes()


def test_the_state_starts_again_after_each_stretch_outside_speech_warmed_on_it() -> None:
    model = Model()
    ep = SileroEndpointer(vad=model, reset_frames=4)  # type: ignore[arg-type]
    ep.gain = 2.0
    for k in range(7):
        ep.process(_frame(k))
    # after the 4th quiet frame: started again and heard frames 0-3 once more; then frames 4-6 as they came
    assert model.resets == 1
    assert model.heard == [(_frame(k), 2.0) for k in (0, 1, 2, 3, 4, 5, 6)]
    ep.process(_frame(7))
    assert model.resets == 2 and model.heard == [(_frame(k), 2.0) for k in (4, 5, 6, 7)]


def test_not_within_speech_nor_an_onset_and_counted_afresh_after_an_utterance() -> None:
    model = Model()
    ep = SileroEndpointer(vad=model, reset_frames=3, start_frames=2, end_frames=2)  # type: ignore[arg-type]
    ep.process(QUIET)
    ep.process(QUIET)
    model.p = 0.9  # an onset, then speech, however long
    for _ in range(10):
        ep.process(QUIET)
    assert ep.in_speech and model.resets == 0
    model.p = 0.0
    for _ in range(2):  # the utterance's end
        ep.process(QUIET)
    assert not ep.in_speech and model.resets == 0
    for _ in range(2):  # quiet frames before the utterance did not count
        ep.process(QUIET)
    assert model.resets == 0
    ep.process(QUIET)
    assert model.resets == 1


def test_none_never_starts_again() -> None:
    model = Model()
    ep = SileroEndpointer(vad=model)  # type: ignore[arg-type]
    for _ in range(500):
        ep.process(QUIET)
    assert model.resets == 0


def _ended_after(config: SegmenterConfig, lead_s: float) -> float:
    """A "stop" after `lead_s` of a quiet room's hiss: how long after its speech ends (s) the segment ends."""
    speech = np.frombuffer(read_wav(synth.speech_clip("stop", "en-us", 150).path), "<i2") / 32768.0
    loud = np.flatnonzero(np.abs(speech) > 0.02 * np.abs(speech).max())
    speech = speech[loud[0] : loud[-1] + 1] * 0.1 / np.abs(speech).max()
    x = np.random.default_rng(1).normal(0.0, 10 ** (-70 / 20), int((lead_s + 2.0) * SAMPLE_RATE))
    at = int(lead_s * SAMPLE_RATE)
    x[at : at + speech.size] += speech
    pcm, seg = to_pcm(np.clip(x, -1.0, 1.0)), Segmenter(config)
    segments = [s for k in range(0, len(pcm), 960) for s in seg.feed(pcm[k : k + 960])] + seg.flush()
    (word,) = [s for s in segments if s.end_s > lead_s]
    return word.end_s - (at + speech.size) / SAMPLE_RATE


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_word_after_a_long_quiet_ends_as_in_a_new_stream_only_with_the_reset() -> None:
    """Measured: after 40 s of a -70 dBFS hiss Silero's drifted state ends the word 0.53 s after its speech (0.09 s
    after 1.5 s); started again every second, 0.08 s."""
    fresh = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=None), 1.5)
    drifted = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=None), 40.0)
    reset = _ended_after(SegmenterConfig(vad_reset_s=1.0, vad_fresh_end_s=None), 40.0)
    assert fresh < 0.2 and reset < 0.2
    assert drifted > fresh + 0.15


# ------------------------------------------------------------------- a fresh state ends words (round voice50b)
def _two_states(fresh_end_frames: int = 3) -> tuple[Model, Model, SileroEndpointer]:
    drifted, ender = Model(), Model()
    ep = SileroEndpointer(vad=drifted, ender=ender, fresh_end_frames=fresh_end_frames,  # type: ignore[arg-type]
                          start_frames=2, end_frames=2)
    return drifted, ender, ep


def _run(ep: SileroEndpointer, drifted: Model, ender: Model, probabilities: list[tuple[float, float]]) -> list[bool]:
    """Feed one frame per (drifted, ender) probability pair; whether the endpointer is in speech after each."""
    out = []
    for p, q in probabilities:
        drifted.p, ender.p = p, q
        ep.process(QUIET)
        out.append(ep.in_speech)
    return out


def test_an_utterance_the_fresh_state_heard_ends_where_it_hears_it_end() -> None:
    drifted, ender, ep = _two_states()
    # the drifted state runs on (0.9 to the end); the fresh one heard the word and hears it end at the 5th frame
    states = _run(ep, drifted, ender, [(0.9, 0.9), (0.9, 0.9), (0.9, 0.9), (0.9, 0.9), (0.9, 0.1), (0.9, 0.1)])
    assert states == [False, True, True, True, True, False]


def test_an_utterance_the_fresh_state_did_not_hear_ends_by_the_drifted_one() -> None:
    """Round voice50: a restarted state hears almost nothing of quiet words over a noisy floor; those the drifted state
    starts, and only it can end them."""
    drifted, ender, ep = _two_states()
    states = _run(ep, drifted, ender, [(0.9, 0.1), (0.9, 0.1), (0.9, 0.1), (0.9, 0.1), (0.1, 0.1), (0.1, 0.1)])
    assert states == [False, True, True, True, True, False]


def test_the_fresh_state_alone_starts_nothing() -> None:
    drifted, ender, ep = _two_states()
    assert not any(_run(ep, drifted, ender, [(0.1, 0.9)] * 6))


def test_the_fresh_state_starts_again_outside_speech_warmed_and_the_drifted_one_never() -> None:
    drifted, ender, ep = _two_states(fresh_end_frames=3)
    for k in range(3):
        ep.process(_frame(k))
    assert (drifted.resets, ender.resets) == (0, 1)
    assert ender.heard == [(_frame(k), 1.0) for k in range(3)]  # warmed on the frames it had just heard
    _run(ep, drifted, ender, [(0.9, 0.9)] * 10)  # in speech: no restart however long
    assert (drifted.resets, ender.resets) == (0, 1)
    _run(ep, drifted, ender, [(0.1, 0.1)] * 4)  # the end (2 frames), then 2 outside: counted afresh
    assert ender.resets == 1
    _run(ep, drifted, ender, [(0.1, 0.1)])
    assert (drifted.resets, ender.resets) == (0, 2)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_word_after_a_long_quiet_ends_as_in_a_new_stream_with_a_fresh_state_ending_it() -> None:
    fresh = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=None), 1.5)
    drifted = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=None), 40.0)
    ended = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=1.0), 40.0)
    assert ended < 0.2 and fresh < 0.2
    assert drifted > ended + 0.15


def test_an_utterance_the_fresh_state_is_not_trusted_with_ends_by_the_drifted_one_and_arms_no_hold() -> None:
    """`ender_trusted` (the segmenter's `vad_fresh_end_snr_db`: an utterance not clear of the noise) leaves the end to
    the first state, as if the fresh one had not heard the word."""
    drifted, ender, ep = _two_states()
    ep.ender_trusted = False
    states = _run(ep, drifted, ender, [(0.9, 0.9)] * 4 + [(0.9, 0.1)] * 2 + [(0.1, 0.1)] * 2)
    assert states == [False, True, True, True, True, True, True, False]
    assert _run(ep, drifted, ender, [(0.9, 0.1)] * 2)[-1]  # no hold after it: the drifted state starts the next


def test_after_the_fresh_state_ended_a_word_the_drifted_states_run_on_starts_nothing_but_a_new_word_does() -> None:
    drifted, ender, ep = _two_states()
    _run(ep, drifted, ender, [(0.9, 0.9)] * 4 + [(0.9, 0.1)] * 2)  # ended by the fresh state
    assert not any(_run(ep, drifted, ender, [(0.9, 0.1)] * 5))  # the drifted state's stale speech
    assert _run(ep, drifted, ender, [(0.9, 0.9)] * 2)[-1]  # a word the fresh state hears starts at once
    _run(ep, drifted, ender, [(0.9, 0.1)] * 2 + [(0.1, 0.1)])  # ended; the drifted state then hears the end too
    assert _run(ep, drifted, ender, [(0.9, 0.1)] * 2)[-1]  # and starts utterances again on its own


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_with_a_clear_speech_bar_the_fresh_state_ends_only_a_word_that_clears_it() -> None:
    """A -20 dBFS "stop" over a -70 dBFS hiss is about 35 dB over it: with the bar at 30 dB the fresh state ends it;
    with a bar no word clears, the drifted state does, late."""
    clear = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=1.0, vad_fresh_end_snr_db=30.0), 40.0)
    unclear = _ended_after(SegmenterConfig(vad_reset_s=None, vad_fresh_end_s=1.0, vad_fresh_end_snr_db=80.0), 40.0)
    assert clear < 0.2
    assert unclear > clear + 0.15


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_by_default_a_clear_word_after_a_long_quiet_ends_as_in_a_new_stream() -> None:
    """Round voice50d: the fresh state, trusted with a word 30 dB over the floor, is the default."""
    assert (SegmenterConfig().vad_fresh_end_s, SegmenterConfig().vad_fresh_end_snr_db) == (1.0, 30.0)
    assert _ended_after(SegmenterConfig(), 40.0) < 0.2


SETTINGS = [("vad_reset", "vad_reset_s", "HRI_VOICE_VAD_RESET", "0.1"),
            ("vad_fresh_end", "vad_fresh_end_s", "HRI_VOICE_VAD_FRESH_END", "0.1"),
            ("vad_fresh_end_snr", "vad_fresh_end_snr_db", "HRI_VOICE_VAD_FRESH_END_SNR", "-1")]


@pytest.mark.parametrize(("setting", "field", "variable", "too_low"), SETTINGS)
@pytest.mark.parametrize(("raw", "value"), [(None, "default"), ("off", None), ("1", 1.0), (" 2.5 ", 2.5)])
def test_the_setting(setting: str, field: str, variable: str, too_low: str, raw: str | None,
                     value: float | str | None) -> None:
    expected = getattr(SegmenterConfig, field) if value == "default" else value
    assert getattr(VoiceSettings(**{setting: raw}).segmenter(), field) == expected


@pytest.mark.parametrize(("setting", "field", "variable", "too_low"), SETTINGS)
@pytest.mark.parametrize("raw", ["too low", "61", "soon", "nan"])
def test_a_bad_setting_names_the_variable(setting: str, field: str, variable: str, too_low: str, raw: str) -> None:
    with pytest.raises(EngineError, match=variable):
        VoiceSettings(**{setting: too_low if raw == "too low" else raw}).segmenter()
