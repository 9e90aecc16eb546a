"""The robot's own voice taken out of the microphone's stream: echo cancellation, the played sound as the reference.

The microphone in the OP2's head hears the robot's loudspeaker louder than any person, so a person's "stop" said over
the robot's voice was seldom heard (`bench/voice_own.py --over`: 1-8 of 47). An echo canceller learns the way from
the loudspeaker to the microphone (the sound card's delay, the loudspeaker, the room) from the sound the robot played
and subtracts its estimate of that sound from what the microphone heard, leaving the person. It needs the played
sound sample for sample: the speech service says what it says (`SpeechState.text`) and with which espeak-ng voice and
rate (its health), and espeak-ng renders the same text to the same samples every time, so the voice process renders
it again (`robot_voice.RobotVoice`, onto `Played`). The state says when the robot began only to within tens of ms,
so each sentence is placed where its echo is found in the stream (`EchoCanceller.lock`); while it is looked for
(0.72 s) the stream is held back, then learnt from and cancelled from the sentence's first sample
(`EchoCanceller.look_back`, `learn_first`).

The canceller is speexdsp's (its multi-delay block frequency-domain filter, bundled in the `pyaec` wheel), on 10 ms
frames, with a 256 ms filter: the sound card's delay and the room's first reflections fit in it. It runs on every
frame of a live stream, so that what it learnt in one sentence is there at the start of the next; where no played
sound lies within the filter's reach, its output is not used and the stream goes on as the microphone heard it. What it
learnt from (its last 6 s of the robot's voice, `EchoCanceller.memory`) is kept in the state folder and learnt from
again when the next run starts (`EchoMemory`, round voice48), so that a run's first sentence is cancelled too. With
`HRI_VOICE_ECHO_FIT` (round voice49, `echo_fit.py`) the whole way is also fitted on that memory by least squares and
subtracted before speexdsp's filter, which then learns only what the fit leaves.
"""

from __future__ import annotations

import os
import threading
import time
import zipfile
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from services.runtime.flags import parse_flag
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH
from services.voice.echo_fit import FittedPath, fit_path

FRAME = 160
"""Samples per frame the canceller takes (10 ms at 16 kHz)."""
FILTER_S = 0.256
"""The canceller's filter: how long after the played sound its echo may still be learnt."""
LEAD_S = 0.02
"""Each sentence's reference is placed this long before its echo was found in the stream: the canceller can only use a
reference that comes before its echo, and the same lead every sentence keeps what it learnt in place."""
LOCK_S = 0.3
"""How much of a sentence is heard before its echo is looked for (`lock`): enough of the robot's voice to find it by
correlation. Until then, with the search's reach after the state (0.6 s in all), the stream is held back and cancelled
once the echo is found (`EchoCanceller.look_back`), or passed on as heard without it."""
SEARCH_S = (-0.1, 0.3)
"""Where the echo is looked for, against when the speech service said the sentence began (by the stream's clock): the
state arrives over the bus after the sound card started, or before it (a player's start-up), and the stream's clock is
good to a block."""
RENDER_WAIT_S = 1.5
"""How long past a sentence's state the stream is held back at most while its reference is still being rendered
(`Played.expect`; 14-18 ms a sentence, but the speech service's health is asked first, with a 1 s timeout, and a
loaded machine takes longer): a renderer that hangs does not hold the stream for good."""
MIN_CORRELATION = 0.3
"""A sentence whose echo correlates less with it (the microphone does not hear the loudspeaker: a headset; a person
louder than the robot) is not cancelled."""
KEPT = 8
"""Sentences kept (the robot speaks one at a time; a few cover any overlap)."""
MEMORY_S = 6.0
"""How much of the robot's voice the canceller remembers (`EchoCanceller.memory`): the last this many seconds it
cancelled, reference and microphone, about three sentences."""
INSTALL = "pip install pyaec (speexdsp's echo canceller in a wheel; Linux x86_64)"


ENV = "HRI_VOICE_ECHO_CANCEL"
DEFAULT_ON = True
MEMORY_ENV = "HRI_VOICE_ECHO_MEMORY"
MEMORY_FILE = "echo-memory.npz"
"""In the state folder: the canceller's `memory`, saved each time the robot falls silent, `recall`ed at start."""
MEMORY_DEFAULT_ON = True
"""Whether `HRI_VOICE_ECHO_MEMORY` is on when unset: on since round voice48 (voice README), which it passed."""
FIT_ENV = "HRI_VOICE_ECHO_FIT"
FIT_DEFAULT_ON = True
"""Whether `HRI_VOICE_ECHO_FIT` (`EchoCanceller.fit`) is on when unset: on since round voice49 (voice README), which it
passed."""


class EchoError(RuntimeError):
    """The canceller cannot run here (its library is missing), or its setting is not on or off."""


def echo_cancel_from(raw: str | None, env: str = ENV) -> bool:
    """`HRI_VOICE_ECHO_CANCEL` / `--echo-cancel` (`env`: the variable a bad value is reported as): on (the default) or
    off."""
    if raw is None or raw.strip() == "":
        return DEFAULT_ON
    value = parse_flag(raw)
    if value is None:
        raise EchoError(f"{env}={raw!r}: on or off")
    return value


def echo_memory_from(raw: str | None) -> bool:
    """`HRI_VOICE_ECHO_MEMORY` / `--echo-memory`: on or off; unset: `MEMORY_DEFAULT_ON`."""
    if raw is None or raw.strip() == "":
        return MEMORY_DEFAULT_ON
    return echo_cancel_from(raw, MEMORY_ENV)


def echo_fit_from(raw: str | None) -> bool:
    """`HRI_VOICE_ECHO_FIT` / `--echo-fit`: on or off; unset: `FIT_DEFAULT_ON`."""
    if raw is None or raw.strip() == "":
        return FIT_DEFAULT_ON
    return echo_cancel_from(raw, FIT_ENV)


@dataclass
class EchoMemory:
    """The canceller's `memory` in a file (NumPy's npz: `mic`, `ref`), so that the next run's canceller `recall`s it.
    The file holds up to `MEMORY_S` of what the microphone heard while the robot spoke, a person talking over it
    included: it stays in the state folder, and `HRI_VOICE_ECHO_MEMORY=off` neither reads nor writes it."""

    path: Path

    def write(self, memory: tuple[np.ndarray, np.ndarray]) -> None:
        """A canceller's `memory()` to the file, written whole or not at all (a temporary file renamed over it); an empty
        one is not written. OSError where it cannot be written."""
        mic, ref = memory
        if not mic.size:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        with tmp.open("wb") as f:
            np.savez(f, mic=mic, ref=ref)
        os.replace(tmp, self.path)

    def recall(self, canceller: EchoCanceller) -> bool:
        """The canceller learns from the file's memory, if there is a file (False if not). ValueError naming the file
        for one that is not such a memory (the canceller then has learnt nothing from it); OSError where it cannot be
        read."""
        if not self.path.is_file():
            return False
        try:
            with np.load(self.path, allow_pickle=False) as data:
                mic, ref = np.asarray(data["mic"]), np.asarray(data["ref"])
            canceller.recall(mic, ref)
        except (ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:  # not an npz (or cut short), one without
            # the two arrays, or other samples
            raise ValueError(f"{self.path}: not an echo memory ({exc})") from None
        return True


@dataclass
class Sentence:
    """One sentence the robot played: its samples (float, 16 kHz), when it began (wall clock, UNIX seconds), and once
    its echo has been found (`EchoCanceller.lock`), where it is placed in the stream (a sample index, fixed, so that
    the reference runs on sample for sample while the stream's clock estimate moves by a few ms)."""

    began: float
    samples: np.ndarray
    at: int | None = None
    """Where the speech service's state puts it in the stream (set when the canceller first sees it)."""
    placed: int | None = None
    """Where its echo was found, less the lead; None until then. (Placing it meanwhile where the last sentence's echo
    was, after its state, heard fewer "stop"s than not: the sound card's delay and the state's way vary by tens of
    ms from one sentence to the next, and a reference that far off unlearns the canceller's filter.)"""
    lost: bool = False
    """Its echo was looked for and not found: it is not cancelled."""
    heard_at: float | None = None
    """When its echo began (wall clock, UNIX seconds): when the state said it began, and the lag at which its echo
    was found; None until then."""
    stops: tuple[tuple[float, float], ...] = ()
    """When the robot says "stop" (or "stopped") in it: from, to, seconds into `samples` (`robot_voice.stop_words`);
    set once known, after the sentence is added."""


@dataclass
class Played:
    """The robot's played sound: sentences added as they begin (`robot_voice.RobotVoice`), read by the canceller.

    A sentence is `expect`ed as its state arrives and `add`ed once rendered: until then the canceller holds the stream
    back from where its echo may begin (`EchoCanceller.reference`), for up to `RENDER_WAIT_S`. Without that, a render
    that took longer than usual (a loaded machine: 0.5 s is enough) let the sentence's first part through uncancelled,
    and a person's "stop" said over it with it (it failed CI once, stop 104)."""

    _sentences: deque[Sentence] = field(default_factory=lambda: deque(maxlen=KEPT))
    _awaited: list[float] = field(default_factory=list)
    """When each sentence begun but not rendered yet began (wall clock)."""
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def expect(self, began: float) -> None:
        """A sentence began at wall-clock `began`; its samples are on their way (`add`, or `forget` if they never
        come)."""
        with self._lock:
            self._awaited = [*self._awaited[-(KEPT - 1) :], began]

    def add(self, began: float, samples: np.ndarray) -> Sentence:
        """`samples` (float, 16 kHz) began at wall-clock `began` (no longer awaited, if it was)."""
        sentence = Sentence(began, np.asarray(samples, dtype=np.float32))
        with self._lock:
            self._sentences.append(sentence)
            self._drop(began)
        return sentence

    def forget(self, began: float) -> None:
        """The sentence `expect`ed at `began` will not be rendered (or already was): it is no longer awaited."""
        with self._lock:
            self._drop(began)

    def _drop(self, began: float) -> None:
        if began in self._awaited:
            self._awaited.remove(began)

    def sentences(self) -> list[Sentence]:
        with self._lock:
            return list(self._sentences)

    def awaited(self) -> list[float]:
        """When each sentence `expect`ed and not yet added or forgotten began (wall clock)."""
        with self._lock:
            return list(self._awaited)


def echo_lag(played: np.ndarray, heard: np.ndarray) -> tuple[int, float]:
    """Where in `heard` `played` best lines up (its offset in samples) and how well (the normalised correlation of that
    stretch with it, 0 to 1)."""
    n = played.size
    if heard.size < n or not np.any(played):
        return 0, 0.0
    size = 1 << int(np.ceil(np.log2(heard.size + n)))
    corr = np.fft.irfft(np.fft.rfft(heard, size) * np.conj(np.fft.rfft(played, size)), size)[: heard.size - n + 1]
    energy = np.concatenate([[0.0], np.cumsum(heard.astype(np.float64) ** 2)])
    window = energy[n:] - energy[:-n]
    score = np.abs(corr) / (np.sqrt(np.maximum(window, 1e-12)) * np.linalg.norm(played) + 1e-12)
    best = int(np.argmax(score))
    return best, float(score[best])


def _aec(filter_s: float) -> object:
    try:
        from pyaec import Aec  # imported here: only a live stream with the canceller on needs it
    except (ImportError, AttributeError) as exc:  # pyaec raises AttributeError when its library will not load
        raise EchoError(f"the echo canceller is not installed ({exc}): {INSTALL}") from None
    # speex's preprocessor (noise and residual echo suppression) stays off: on a probe it took a person's "stop" away
    # with the echo (stop 86, `docs/experiments/scripts/voice45_aec_probe.py`)
    return Aec(FRAME, int(filter_s * SAMPLE_RATE), SAMPLE_RATE, False)


@dataclass
class _Stages:
    """What cancels: speexdsp's adaptive filter, after the fitted way where there is one (`EchoCanceller.fit`)."""

    aec: object
    path: FittedPath | None = None
    fit_db: float | None = None


@dataclass
class EchoCanceller:
    """A live stream's chunks in, the same samples out with the robot's played sound cancelled where there was some.
    Samples come out in whole frames: up to 9 ms of a chunk waits for the next one."""

    played: Played
    filter_s: float = FILTER_S
    lead_s: float = LEAD_S
    frames: int = 0
    """Frames the canceller's output was used for (the robot's voice within its reach)."""
    erle_db: float | None = None
    """How far the last stretch of the robot's voice was taken down (output over input energy, dB; the echo return
    loss enhancement): about -20 once the way is learnt, near 0 while it is not or when the reference is wrong."""
    locked: int = 0
    """Sentences whose echo was found, and so are cancelled."""
    lost: int = 0
    """Sentences whose echo was not found (or found too late), not cancelled."""
    lag_ms: float | None = None
    """How long after the speech service's state said the last sentence began its echo was heard."""
    look_back: bool = True
    """While a sentence's echo is looked for (from where it may begin until `LOCK_S` and the search's reach after its
    state: 0.72 s, in whole blocks of the stream), the stream is held back, then cancelled from the sentence's first
    sample once the echo is found, so that a person's "stop" said over the start of a sentence is cancelled too; what
    the stream held is then passed on at once, with its place in the stream unchanged. False: the stream goes on as
    heard meanwhile, uncancelled, and nothing is held."""
    learn_first: bool = True
    """With `look_back`: what was held is run through the canceller twice, first to learn the way from it (the output
    dropped), then, after the filter's length of silence on both sides (so that the second run does not begin with the
    end of the first in the filter's memory), for the stream. A canceller that has not heard the robot yet (the voice
    service just started, the robot's first sentence) thus learns from the sentence's first 0.6 s before cancelling
    them; one that has, learns them twice. It costs one more run over the hold and the silence (about 9 ms a
    sentence). On since round voice47b (voice README): it heard more "stop"s over a canceller that had heard the robot
    before, and no fewer cold."""
    held_ms: float | None = None
    """How long the stream was last held back while a sentence's echo was looked for."""
    recalled_s: float = 0.0
    """Seconds of the robot's voice learnt from before the stream began (`recall`: an earlier run's `memory`)."""
    fit: bool = FIT_DEFAULT_ON
    """Round voice49: a fixed estimate of the way (`echo_fit`), fitted by least squares on the `memory` each time a
    stretch of the robot's voice ends and when one is `recall`ed, subtracted before speexdsp's filter; each fit comes
    with a new speexdsp filter that has learnt the memory through it (the old one had learnt what the old fit left, and
    would add that back)."""
    background: bool = False
    """With `fit`: a fit after a stretch of the robot's voice is made on a thread of its own and put in use at the first
    block after it is ready that lies outside the robot's voice (the service: a fit and the new filter's lesson took
    0.26-0.6 s on a 2-core AVX2 machine beside a bench, far longer than a stream's block should wait; the stream's
    thread runs meanwhile, `echo_fit.solve_toeplitz`). False: at once, on the caller's thread (the bench, whose streams
    run faster than real time)."""
    fits: int = 0
    """Fits put in use."""
    robot_near: bool = False
    """Whether the robot's voice may lie in the samples last passed on: a placed sentence within the filter's reach of
    them, or one whose echo may have begun and has not been found yet. With `SegmenterConfig.floor_hold` the segmenter
    holds its noise floor over them: what the canceller leaves of the robot's voice is not the room's noise."""
    fit_ms: float | None = None
    """How long the last fit took, the new filter's lesson included."""
    on_silent: Callable[[EchoCanceller], None] | None = field(default=None, repr=False)
    """Called (on the stream's thread) each time a stretch of the robot's voice has ended and passed out of the
    filter's reach: the service saves the canceller's `memory` then."""
    _stages: _Stages = field(init=False, repr=False)
    _ready: _Stages | None = field(default=None, repr=False)
    """A fit made in the `background`, waiting to be put in use."""
    _fitting: threading.Thread | None = field(default=None, repr=False)
    _held: bytes = b""
    _index: int = 0
    """Samples of the stream seen so far; the held ones (`_held`) come after them."""
    _recent: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.float32), repr=False)
    _keep_n: int = 4 * SAMPLE_RATE
    _unplaced: bool = False
    """A sentence's echo may have begun and has not been found yet."""
    _pending: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int16), repr=False)
    """The stream held back (`look_back`): the samples just before `_index`'s held ones."""
    _energy: tuple[float, float] = (0.0, 0.0)
    """Input and output energy of the current stretch of the robot's voice."""
    _memory: tuple[np.ndarray, np.ndarray] = field(
        default_factory=lambda: (np.zeros(0, dtype=np.int16), np.zeros(0, dtype=np.int16)), repr=False
    )

    def __post_init__(self) -> None:
        self._stages = _Stages(_aec(self.filter_s))

    def __call__(self, chunk: bytes, captured: float | None) -> bytes:
        """`chunk` (16-bit PCM, 16 kHz) whose first sample was captured at wall-clock `captured` (None: not known
        yet, or the stream has ended: passed on as it is, after what was held back)."""
        if captured is None:
            self.robot_near = False  # the stream has ended (or its clock is not known yet): nothing is placed
            held, self._held = self._held, b""
            pending, self._pending = self._pending.tobytes(), self._pending[:0]
            self._keep(np.frombuffer(held + chunk, "<i2"))
            return pending + held + chunk
        # the wall clock of the stream's sample 0, as the stream's clock says now
        origin = captured - (self._index + len(self._held) // SAMPLE_WIDTH) / SAMPLE_RATE
        pcm = self._held + chunk
        whole = len(pcm) - len(pcm) % (FRAME * SAMPLE_WIDTH)
        self._held = pcm[whole:]
        new = np.frombuffer(pcm[:whole], "<i2")
        if new.size == 0:
            return b""
        self._keep(new)
        mic = np.concatenate([self._pending, new]) if self._pending.size else new
        first = self._index - mic.size  # the stream's index of the first sample to pass on
        ref, near = self.reference(first, mic.size, origin)
        if self._unplaced and self.look_back:  # held until the echo is found, then cancelled from its start
            self._pending = mic
            return b""
        self.robot_near = near or self._unplaced
        out = mic.copy()
        refs = np.round(np.clip(ref, -1.0, 1.0) * 32767).astype(np.int16)
        if self._pending.size:
            self.held_ms = round(self._pending.size / SAMPLE_RATE * 1000.0, 1)
            self._pending = self._pending[:0]
            if self.learn_first and near:
                self._run(mic, refs)
                self._silence()
        if self._unplaced:  # not fed: its echo with no reference would unlearn what the canceller learnt
            self._measure(mic, out, False)
            return out.tobytes()
        cancelled = self._run(mic, refs)
        if near:
            out = cancelled
            self.frames += mic.size // FRAME
            self._remember(mic, refs)
        self._measure(mic, out, near)
        return out.tobytes()

    def _run(self, mic: np.ndarray, refs: np.ndarray, stages: _Stages | None = None) -> np.ndarray:
        """The canceller (`stages`, else the one in use) over whole frames of the microphone's samples and the
        reference's: its output. (speexdsp reads a whole frame whatever it is given: a short one crashes the
        process.)"""
        assert mic.size % FRAME == 0 and refs.size == mic.size
        stages = self._stages if stages is None else stages
        if stages.path is not None:
            mic = stages.path.cancel(mic, refs)
        out = np.empty_like(mic)
        for k in range(0, mic.size, FRAME):
            out[k : k + FRAME] = stages.aec.cancel_echo(mic[k : k + FRAME].tolist(), refs[k : k + FRAME].tolist())  # type: ignore[attr-defined]
        return out

    def _silence(self, stages: _Stages | None = None) -> None:
        """The filter's length of silence through the canceller: what it ran before is out of its memory."""
        silence = np.zeros((int(self.filter_s * SAMPLE_RATE) // FRAME + 1) * FRAME, dtype=np.int16)
        self._run(silence, silence, stages)

    def _remember(self, mic: np.ndarray, refs: np.ndarray) -> None:
        keep = int(MEMORY_S * SAMPLE_RATE) // FRAME * FRAME
        self._memory = (np.concatenate([self._memory[0], mic])[-keep:], np.concatenate([self._memory[1], refs])[-keep:])

    def memory(self) -> tuple[np.ndarray, np.ndarray]:
        """The last `MEMORY_S` of the robot's voice this canceller cancelled: the microphone's samples and the reference
        it was given for them (16-bit, whole frames), for `recall` by the next run."""
        return self._memory[0].copy(), self._memory[1].copy()

    def recall(self, mic: np.ndarray, refs: np.ndarray) -> None:
        """Learn the way from the loudspeaker to the microphone from an earlier run's `memory` (the output dropped), then
        the filter's length of silence: the robot's first sentence is cancelled by a filter that has heard it before.
        The way through the robot's head changes little from run to run; the room's part of it may (a recall from
        another room is measured in the voice README). ValueError for samples that are not such a memory."""
        mic, refs = np.asarray(mic), np.asarray(refs)
        if mic.dtype != np.int16 or refs.dtype != np.int16 or mic.ndim != 1 or mic.shape != refs.shape:
            raise ValueError(f"not an echo memory: {mic.dtype}{mic.shape} and {refs.dtype}{refs.shape}, "
                             "two 16-bit sample arrays of one length expected")
        if mic.size % FRAME or mic.size > int(MEMORY_S * SAMPLE_RATE):
            raise ValueError(f"not an echo memory: {mic.size} samples, whole {FRAME}-sample frames up to "
                             f"{MEMORY_S} s expected")
        if mic.size:
            self._memory = (mic.copy(), refs.copy())
            if not self._refit():
                self._run(mic, refs)
                self._silence()
            self.recalled_s = round(mic.size / SAMPLE_RATE, 2)

    @property
    def fit_db(self) -> float | None:
        """How far the fit in use took the memory's own echo down (dB); None while there is none."""
        return self._stages.fit_db

    def _refit(self) -> bool:
        """With `fit`, at once: the way fitted again on the `memory` and put in use where it is good enough. True if
        it was."""
        if not self.fit:
            return False
        stages = self._fitted(self._memory)
        if stages is not None:
            self._use(stages)
        return stages is not None

    def _fitted(self, memory: tuple[np.ndarray, np.ndarray]) -> _Stages | None:
        """The way fitted on `memory` and a new speexdsp filter that has learnt `memory` through it; None where the fit
        is not good enough (`echo_fit.MIN_GAIN_DB`)."""
        began = time.perf_counter()
        found = fit_path(*memory, rate=SAMPLE_RATE, taps=int(self.filter_s * SAMPLE_RATE))
        stages = None
        if found is not None:
            stages = _Stages(_aec(self.filter_s), FittedPath(found[0]), found[1])
            self._run(*memory, stages)
            self._silence(stages)
        self.fit_ms = round((time.perf_counter() - began) * 1000.0, 1)
        return stages

    def _fit_later(self, memory: tuple[np.ndarray, np.ndarray]) -> None:
        self._ready = self._fitted(memory)

    def _use(self, stages: _Stages) -> None:
        self._stages = stages
        self.fits += 1

    def _refit_after_voice(self) -> None:
        """A stretch of the robot's voice has ended: with `fit`, fit the way again, at once or in the `background`
        (unless a fit is being made)."""
        if not self.fit:
            return
        if not self.background:
            self._refit()
        elif self._fitting is None or not self._fitting.is_alive():
            self._fitting = threading.Thread(target=self._fit_later, args=(self.memory(),), name="echo-fit", daemon=True)
            self._fitting.start()

    def _keep(self, mic: np.ndarray) -> None:
        """The stream's recent samples, for finding a sentence's echo in them."""
        self._recent = np.concatenate([self._recent, mic.astype(np.float32) / 32768.0])[-self._keep_n :]
        self._index += mic.size

    def reference(self, first: int, n: int, origin: float) -> tuple[np.ndarray, bool]:
        """The played sound for the stream's samples `first` to `first + n`, and whether any of it lies within the
        filter's reach of them. Each sentence is placed by `origin` (the wall clock of the stream's sample 0) when
        first seen, and `lock`ed to its echo once `LOCK_S` of it has been heard; until then (`_unplaced`, from where
        its echo may begin) the stream is held back (`look_back`) or passes as heard, and the canceller is not fed. A
        sentence `Played.expect`ed and not rendered yet is treated so too, up to `RENDER_WAIT_S` past its state."""
        ref = np.zeros(n, dtype=np.float32)
        reach = int(self.filter_s * SAMPLE_RATE)
        near = False
        self._unplaced = False
        for sentence in self.played.sentences():
            if sentence.at is None:
                sentence.at = int(round((sentence.began - origin) * SAMPLE_RATE))
            if sentence.placed is None and not sentence.lost:
                self.lock(sentence)
            if sentence.placed is None or sentence.lost:
                if sentence.placed is None and not sentence.lost and self._may_begin(sentence.at) < first + n:
                    self._unplaced = True  # its echo may be in the stream with no reference for it yet
                continue
            start, end = sentence.placed, sentence.placed + sentence.samples.size
            lo, hi = max(first, start), min(first + n, end)
            if lo < hi:
                ref[lo - first : hi - first] += sentence.samples[lo - start : hi - start]
            near = near or (start < first + n and end + reach > first)
        for began in self.played.awaited():  # begun, not rendered yet: held back as if its echo were being looked for
            at = int(round((began - origin) * SAMPLE_RATE))
            if self._may_begin(at) < first + n and first + n - at <= int(RENDER_WAIT_S * SAMPLE_RATE):
                self._unplaced = True
        return ref, near

    def _may_begin(self, at: int) -> int:
        """Where in the stream the echo of a sentence the state puts at `at` may begin: the search's reach before it,
        less the lead its reference will be placed by."""
        return at + int(SEARCH_S[0] * SAMPLE_RATE) - int(self.lead_s * SAMPLE_RATE)

    def lock(self, sentence: Sentence) -> None:
        """Once the stream holds the sentence's first `LOCK_S` and the search's reach after it, find its echo there
        and place the sentence `lead_s` before it; a sentence whose echo is not found is `lost`."""
        assert sentence.at is not None
        lock = min(int(LOCK_S * SAMPLE_RATE), sentence.samples.size)
        lo = sentence.at + int(SEARCH_S[0] * SAMPLE_RATE)
        hi = sentence.at + int(SEARCH_S[1] * SAMPLE_RATE) + lock
        if hi > self._index:
            return  # not heard yet
        begin = self._index - self._recent.size
        lo = max(lo, begin, 0)  # the stream (or what is kept of it) began within the search's reach
        if hi - lo < lock:  # long gone by the time it was rendered: too late to cancel it
            sentence.lost = True
            self.lost += 1
            return
        lag, score = echo_lag(sentence.samples[:lock], self._recent[lo - begin : hi - begin])
        if score < MIN_CORRELATION:
            sentence.lost = True
            self.lost += 1
            return
        sentence.placed = lo + lag - int(self.lead_s * SAMPLE_RATE)
        sentence.heard_at = sentence.began + (lo + lag - sentence.at) / SAMPLE_RATE
        self.locked += 1
        self.lag_ms = round((lo + lag - sentence.at) / SAMPLE_RATE * 1000.0, 1)

    def _measure(self, mic: np.ndarray, out: np.ndarray, near: bool) -> None:
        if not near and self._ready is not None:  # a fit made in the background, put in use outside the robot's voice
            ready, self._ready = self._ready, None
            self._use(ready)
        into, left = self._energy
        if near:
            self._energy = (into + float(np.sum(mic.astype(np.float64) ** 2)),
                            left + float(np.sum(out.astype(np.float64) ** 2)))
        elif into > 0.0:  # a stretch of the robot's voice has ended
            self.erle_db = round(10.0 * float(np.log10(max(left, 1.0) / into)), 1)
            self._energy = (0.0, 0.0)
            self._refit_after_voice()
            if self.on_silent is not None:
                self.on_silent(self)
