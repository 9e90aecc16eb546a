"""The sound the robot is playing, rendered again in the voice process: the echo canceller's reference.

The speech service publishes what it says (`SpeechState.text`, with `speaking=True` as it starts) and keeps its
espeak-ng voice and rate in its health. espeak-ng renders the same text with the same voice and rate to the same
samples every time (checked sample for sample against the speech service's WAV in `tests/voice/test_echo.py`), so the
voice process renders it again and places it on the wall clock from when the state arrived (`echo.Played`). Its
volume is not needed: the canceller learns the gain from the loudspeaker to the microphone anyway.

A speech service that does not use espeak-ng (its health's `engine` does not name it) or that cannot be asked gives
no reference: that sentence is not cancelled (counted in `unrendered`), and the own-voice gate still holds.
"""

from __future__ import annotations

import queue
import re
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from services.voice.audio import SAMPLE_RATE
from services.voice.echo import Played
from services.voice.espeak_words import Word, words
from services.voice.synth import SynthError, speak

Render = Callable[[str, str, int], np.ndarray]
"""(text, espeak-ng voice, words a minute) -> float samples at 16 kHz."""
Ask = Callable[[], Mapping[str, object] | None]
"""The speech service's health detail now, or None when it does not answer."""

STOP_WORD = re.compile(r"\bstop\w*", re.IGNORECASE)
"""The robot's own words the recogniser may take for "stop" ("stop", "stopped"): the one command the own-voice gate
lets through while the robot speaks (`own_voice.py`), so the only one it can publish of the robot's own voice."""
SPEECH_DB = -40.0
"""Where a rendering's speech ends: its last sample within this of its loudest."""

Words = Callable[[str, str, int], list[Word]]
"""(text, espeak-ng voice, words a minute) -> espeak-ng's words, each with when it begins (`espeak_words.words`)."""


def speech_end_s(x: np.ndarray) -> float:
    """Where the speech in `x` (16 kHz) ends: its last sample within `SPEECH_DB` of its loudest."""
    loud = np.flatnonzero(np.abs(x) > 10 ** (SPEECH_DB / 20) * (np.max(np.abs(x)) if x.size else 0.0))
    return (int(loud[-1]) + 1) / SAMPLE_RATE if loud.size else 0.0


def stop_words(text: str, said: list[Word], end_s: float) -> tuple[tuple[float, float], ...]:
    """When the robot says each of its `STOP_WORD`s in `text` (from, to; seconds into the sound), from espeak-ng's
    words of it (`said`): from the word's beginning to the next word's, or to the speech's end (`end_s`) for the
    last. A word espeak-ng does not report is left out. No such word: ()."""
    spans = []
    for match in STOP_WORD.finditer(text):
        k = next((k for k, w in enumerate(said) if w.start <= match.start() < w.start + max(w.length, 1)), None)
        if k is not None:
            until = said[k + 1].at_s if k + 1 < len(said) else end_s
            spans.append((said[k].at_s, max(said[k].at_s, until)))
    return tuple(spans)


@dataclass
class RobotVoice:
    """Fed the speech service's states (`heard`, from the bus's thread); `run` renders each sentence begun onto
    `played` on its own thread."""

    played: Played
    ask: Ask
    render: Render = field(default=speak)
    clock: Callable[[], float] = field(default=time.time, repr=False)
    words: Words = field(default=words)
    """espeak-ng's words of a sentence, each with when it is said: where the robot says "stop" (`stop_words`)."""
    rendered: int = 0
    unrendered: int = 0
    unworded: int = 0
    """Sentences saying "stop" whose words espeak-ng's library would not time (`espeak_words`): a "stop" heard in
    them is published, as any."""
    last_ms: float | None = None
    """How long the last sentence took to ask about and render: the canceller holds the stream back meanwhile
    (`echo.Played.expect`, up to `echo.RENDER_WAIT_S`)."""
    _begun: queue.Queue[tuple[float, str]] = field(default_factory=lambda: queue.Queue(maxsize=8))

    def heard(self, speaking: bool, text: str | None) -> None:
        """A `SpeechState`, as it arrives."""
        if speaking and text:
            began = self.clock()
            self.played.expect(began)  # the canceller holds the stream back until it is rendered (`Played.expect`)
            try:
                self._begun.put_nowait((began, text))
            except queue.Full:  # the renderer is stuck: that sentence goes without a reference
                self.played.forget(began)
                self.unrendered += 1

    def run(self, stopping: threading.Event) -> None:
        while not stopping.is_set():
            try:
                began, text = self._begun.get(timeout=0.25)
            except queue.Empty:
                continue
            try:
                self.render_one(began, text)
            except Exception:  # espeak-ng hung or died, or the bus went: this sentence goes without a reference
                self.unrendered += 1

    def render_one(self, began: float, text: str) -> None:
        try:
            self._render_one(began, text)
        finally:  # rendered (`add` took it off already) or not: the canceller no longer waits for it
            self.played.forget(began)

    def _render_one(self, began: float, text: str) -> None:
        detail = self.ask() or {}
        engine, voice, rate = str(detail.get("engine") or ""), detail.get("voice"), detail.get("rate")
        if "espeak" not in engine.lower() or not isinstance(voice, str) or not isinstance(rate, int):
            self.unrendered += 1
            return
        try:
            samples = self.render(text, voice, rate)
        except SynthError:
            self.unrendered += 1
            return
        sentence = self.played.add(began, samples)
        self.rendered += 1
        self.last_ms = round((self.clock() - began) * 1000.0, 1)
        if STOP_WORD.search(text):  # after the reference is in place: the canceller waits for that, the gate not yet
            try:
                sentence.stops = stop_words(text, self.words(text, voice, rate), speech_end_s(samples))
            except (SynthError, AttributeError, OSError):  # the library failed (a missing symbol, say): the sentence
                self.unworded += 1  # is cancelled all the same, and its "stop"s are published

    def detail(self) -> dict[str, object]:
        return {"echo_rendered": self.rendered, "echo_unrendered": self.unrendered, "echo_render_ms_last": self.last_ms,
                "echo_unworded": self.unworded}
