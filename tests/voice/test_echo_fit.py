"""The way from the loudspeaker fitted on the echo canceller's memory (`echo_fit`, `EchoCanceller.fit`, round voice49)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from scipy.signal import fftconvolve, lfilter

from services.voice.audio import SAMPLE_RATE
from services.voice.echo import (
    FIT_DEFAULT_ON,
    MEMORY_FILE,
    EchoCanceller,
    EchoError,
    EchoMemory,
    Played,
    echo_fit_from,
)
from services.voice.echo_fit import LOAD, MIN_GAIN_DB, TAPS, FittedPath, fit_path, solve_toeplitz
from tests.voice.test_echo import SENTENCES, _sentences_through, _stream, echo_path, espeak

pytest.importorskip("pyaec")


def _speechlike(rng: np.random.Generator, seconds: float) -> np.ndarray:
    """Noise shaped like speech's spectrum (falling above a few hundred Hz) in bursts, 16-bit."""
    n = int(seconds * SAMPLE_RATE)
    x = lfilter([1.0], [1.0, -0.9], rng.normal(0.0, 1.0, n))
    bursts = (np.sin(np.arange(n) / SAMPLE_RATE * 2 * np.pi * 1.5) > -0.3).astype(float)
    return np.round(np.clip(x * bursts / np.max(np.abs(x)), -1, 1) * 12000).astype(np.int16)


def _through(h: np.ndarray, ref: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    y = fftconvolve(ref.astype(float), h)[: ref.size] + rng.normal(0.0, 2.0, ref.size)
    return np.round(y).astype(np.int16)


def _down_db(before: np.ndarray, after: np.ndarray) -> float:
    return float(10 * np.log10(np.sum(after.astype(float) ** 2) / np.sum(before.astype(float) ** 2)))


def _room(rng: np.random.Generator) -> np.ndarray:
    """20 ms of lead, a direct path and 150 ms of decaying reflections."""
    h = np.zeros(TAPS)
    tail = rng.normal(0.0, 1.0, int(0.15 * SAMPLE_RATE)) * np.exp(-np.arange(int(0.15 * SAMPLE_RATE)) / 400.0) * 0.05
    h[320 : 320 + tail.size] = tail
    h[320] = 0.4
    return h


def test_the_fit_finds_the_way_and_cancels_sound_it_was_not_fitted_on() -> None:
    rng = np.random.default_rng(4)
    h = _room(rng)
    ref = _speechlike(rng, 6.0)
    fitted = fit_path(_through(h, ref, rng), ref, SAMPLE_RATE)
    assert fitted is not None
    taps, gain_db = fitted
    assert taps.size == TAPS and int(np.argmax(np.abs(taps))) == 320 and gain_db < -30.0
    new = _speechlike(np.random.default_rng(5), 3.0)
    heard = _through(h, new, rng)
    assert _down_db(heard, FittedPath(taps).cancel(heard, new)) < -30.0  # -38.4 here


@pytest.mark.parametrize("n", [1, 2, 7, TAPS])
def test_the_levinson_solve_is_scipys_for_speechs_equations(n: int) -> None:
    # the fit's own solver (which lets other threads run between its steps) against SciPy's, on the equations a fit
    # solves: the autocorrelation of speech-like sound, loaded as the fit loads it
    rng = np.random.default_rng(9)
    ref = _speechlike(rng, 3.0).astype(float)
    column = np.correlate(ref, ref[: ref.size - n + 1], mode="valid")
    column[0] *= 1.0 + LOAD
    b = rng.normal(0.0, 1.0, n) * column[0]
    want = scipy.linalg.solve_toeplitz(column, b)
    assert np.max(np.abs(solve_toeplitz(column, b) - want)) <= 1e-9 * np.max(np.abs(want))


def test_the_levinson_solve_refuses_a_matrix_that_is_not_positive_definite() -> None:
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        solve_toeplitz(np.array([1.0, 2.0, 0.5]), np.ones(3))  # |r1| > r0
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        solve_toeplitz(np.array([1.0, 0.9, 0.0]), np.ones(3))  # positive leading 2 x 2 minor, negative 3 x 3


def test_the_fitted_way_runs_the_same_in_a_streams_blocks_as_at_once() -> None:
    rng = np.random.default_rng(6)
    taps = _room(rng)
    ref, mic = _speechlike(rng, 2.0), _speechlike(rng, 2.0)
    whole = FittedPath(taps).cancel(mic, ref)
    path = FittedPath(taps)
    blocks = np.concatenate([path.cancel(mic[k : k + 480], ref[k : k + 480]) for k in range(0, mic.size, 480)])
    assert np.max(np.abs(whole.astype(int) - blocks.astype(int))) <= 1


def test_no_fit_where_there_is_too_little_or_it_does_not_explain_the_microphone() -> None:
    rng = np.random.default_rng(7)
    h = _room(rng)
    ref = _speechlike(rng, 6.0)
    assert fit_path(_through(h, ref, rng)[:8000], ref[:8000], SAMPLE_RATE) is None  # half a second
    assert fit_path(_through(h, ref, rng), np.zeros_like(ref), SAMPLE_RATE) is None  # nothing played
    # the microphone heard something else (a person louder than the robot, another loudspeaker): less than
    # MIN_GAIN_DB explained, and a fit would only add echo
    other = _speechlike(np.random.default_rng(8), 6.0)
    assert MIN_GAIN_DB > 0 and fit_path(other, ref, SAMPLE_RATE) is None


def test_the_echo_fit_setting() -> None:
    assert echo_fit_from(None) is FIT_DEFAULT_ON and echo_fit_from("") is FIT_DEFAULT_ON
    assert echo_fit_from("on") is True and echo_fit_from("off") is False
    with pytest.raises(EchoError, match="HRI_VOICE_ECHO_FIT"):
        echo_fit_from("perhaps")


@espeak
def test_the_canceller_fits_the_way_each_time_the_robot_falls_silent() -> None:
    """With `fit`, each stretch of the robot's voice that ends is followed by a fit on the memory (used where it takes
    the memory's echo down by `MIN_GAIN_DB` or more); the canceller's next sentence is then taken down further than
    without (here -31.3 dB against -22.8 over the third sentence)."""
    path = echo_path(np.random.default_rng(11))
    x, played, starts = _sentences_through(path, SENTENCES, 11)
    third = slice(starts[2], starts[2] + int(2.5 * SAMPLE_RATE))
    down = {}
    for fit in (False, True):
        canceller = EchoCanceller(Played(), fit=fit)
        for s in played.sentences():
            canceller.played.add(s.began, s.samples)
        y = _stream(canceller, x)
        down[fit] = 10 * np.log10(np.sum(y[third] ** 2) / np.sum(x[third] ** 2))
        if fit:
            assert canceller.fits == 3 and canceller.fit_db is not None and canceller.fit_db < -MIN_GAIN_DB
            assert canceller.fit_ms is not None
        else:
            assert canceller.fits == 0 and canceller.fit_db is None
    assert down[True] < down[False] - 6.0, down


@espeak
def test_a_recalled_memory_is_fitted_before_the_first_sentence(tmp_path: Path) -> None:
    """The next run's canceller fits the way on the memory it recalls (and its adaptive filter learns the memory
    through the fit): the robot's first sentence is taken down further than by recalling alone (-32.2 dB against -21.3
    over its first 2.5 s here)."""
    path = echo_path(np.random.default_rng(12))
    x, played, _ = _sentences_through(path, SENTENCES[:2], 12)
    earlier = EchoCanceller(played)
    _stream(earlier, x)
    memory = EchoMemory(tmp_path / MEMORY_FILE)
    memory.write(earlier.memory())
    x, played, [start] = _sentences_through(path, SENTENCES[2:], 13)
    first = slice(start, start + int(2.5 * SAMPLE_RATE))
    down = {}
    for fit in (False, True):
        canceller = EchoCanceller(Played(), fit=fit)
        canceller.played.add(*next((s.began, s.samples) for s in played.sentences()))
        assert memory.recall(canceller)
        assert canceller.fits == int(fit)
        y = _stream(canceller, x)
        down[fit] = 10 * np.log10(np.sum(y[first] ** 2) / np.sum(x[first] ** 2))
    assert down[True] < down[False] - 6.0, down


@espeak
def test_in_the_background_a_fit_is_put_in_use_outside_the_robots_voice() -> None:
    """The service's way (`background`): the fit after a stretch of the robot's voice is made on a thread of its own,
    and put in use once ready, at a block outside the robot's voice."""
    path = echo_path(np.random.default_rng(14))
    x, played, _ = _sentences_through(path, SENTENCES[:1], 14)
    canceller = EchoCanceller(Played(), fit=True, background=True)
    for s in played.sentences():
        canceller.played.add(s.began, s.samples)
    _stream(canceller, x)  # the sentence, then 1 s of hiss: the stretch has ended and a fit is being made
    hiss = np.zeros(int(0.03 * SAMPLE_RATE), dtype="<i2").tobytes()
    at, deadline = 100.0 + x.size / SAMPLE_RATE, time.monotonic() + 30.0
    while canceller.fits == 0 and time.monotonic() < deadline:
        canceller(hiss, at)
        at += 0.03
        time.sleep(0.01)
    assert canceller.fits == 1 and canceller.fit_db is not None and canceller.fit_db < -MIN_GAIN_DB
    assert canceller.fit_ms is not None and canceller.fit_ms > 0.0
