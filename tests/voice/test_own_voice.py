"""The robot's own voice (`services/voice/own_voice.py`): what the microphone hears while the speech service says the
robot is talking, or just after, is not published, "stop" excepted; recordings are heard as they are."""

from __future__ import annotations

import subprocess
import threading
import time
import wave
from collections import deque
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import resample_poly

from schemas.messages import Decision, SpeechRequest, SpeechState, VoiceCommand
from services.runtime import ServiceContext
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, to_pcm
from services.voice.engine import EngineError
from services.voice.own_voice import LONGEST_S, TAIL_S, OwnVoice, OwnVoiceError, tail_from
from services.voice.service import VoiceSettings, check_settings
from services.voice.sources import stream_utterances
from tests.conftest import service_env, wait_for
from tests.voice.test_service import stdin_service


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def spoke(own: OwnVoice, clock: Clock, start: float, end: float) -> None:
    clock.now = start
    own.heard(True)
    clock.now = end
    own.heard(False)


def test_speech_overlapping_the_robots_voice_or_its_tail_is_its_own() -> None:
    clock = Clock()
    own = OwnVoice(tail_s=0.5, clock=clock)
    spoke(own, clock, 110.0, 112.0)
    assert not own.overlaps(108.0, 109.9)  # before it
    assert own.overlaps(109.5, 110.2)  # ends in it
    assert own.overlaps(110.5, 111.5)  # within it
    assert own.overlaps(112.3, 113.0)  # starts in the tail: the room's echo of it
    assert not own.overlaps(112.6, 113.0)  # after the tail: a person answering
    spoke(own, clock, 120.0, 121.0)
    assert own.overlaps(111.0, 111.2) and own.overlaps(120.5, 120.8)  # both spans are kept


def test_while_the_robot_is_still_talking_everything_after_it_began_is_its_own() -> None:
    clock = Clock()
    own = OwnVoice(clock=clock)
    clock.now = 110.0
    own.heard(True)
    own.heard(True)  # a repeated state does not move the start
    assert own.speaking()
    assert own.overlaps(110.5, 111.0) and not own.overlaps(108.0, 109.0)
    # a speech service that died mid-sentence does not leave the robot deaf
    assert not own.overlaps(110.0 + LONGEST_S + TAIL_S + 1.0, 110.0 + LONGEST_S + TAIL_S + 2.0)


def test_not_speaking_alone_is_no_span() -> None:
    clock = Clock()
    own = OwnVoice(clock=clock)
    own.heard(False)  # the speech service's start-up state
    assert not own.speaking() and not own.overlaps(0.0, 1e9)


@pytest.mark.parametrize(("raw", "tail"), [(None, TAIL_S), ("ignore", TAIL_S), ("hear", None), ("HEAR", None),
                                           ("0", 0.0), ("1.5", 1.5)])
def test_the_setting(raw: str | None, tail: float | None) -> None:
    assert tail_from(raw) == tail


@pytest.mark.parametrize("raw", ["-1", "6", "deaf", "nan"])
def test_a_bad_setting_is_refused_at_start_naming_the_variable(raw: str) -> None:
    with pytest.raises(OwnVoiceError, match="HRI_VOICE_OWN_VOICE"):
        tail_from(raw)
    with pytest.raises(EngineError, match="HRI_VOICE_OWN_VOICE"):
        check_settings(VoiceSettings(source="stdin", own_voice=raw))


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_streams_utterance_says_how_long_ago_its_audio_began() -> None:
    """`Utterance.ago_s`, by the stream's clock: the service places the utterance on the wall clock with it, however
    long the segmenter held the utterance after it ended (the end window, the second VAD's 0.5 s)."""
    pcm = synth.recording([synth.speech_clip(w, "en", 130) for w in ("stop", "yes")], gap_s=1.0)
    fed: list[int] = []

    def chunks() -> Iterator[bytes]:
        for at in range(0, len(pcm), 960):
            fed.append(min(at + 960, len(pcm)))
            yield pcm[at : at + 960]

    seen = [(utt, fed[-1]) for utt in stream_utterances(chunks(), "test")]
    assert len(seen) == 2
    for utt, heard in seen:
        assert utt.start_s is not None and utt.ago_s is not None
        assert utt.ago_s == pytest.approx(heard / (2 * SAMPLE_RATE) - utt.start_s)
        assert utt.ago_s >= utt.seconds - 1e-6  # cut once its audio had ended


def _pcm16k(path: Path) -> np.ndarray:
    with wave.open(str(path), "rb") as w:
        rate = w.getframerate()
        x = np.frombuffer(w.readframes(w.getnframes()), "<i2") / 32768.0
    g = np.gcd(rate, SAMPLE_RATE)
    return resample_poly(x, SAMPLE_RATE // g, rate // g)


def _play(proc: subprocess.Popen[bytes], *parts: np.ndarray, gap_s: float = 0.3) -> None:
    """The parts with `gap_s` of a faint hiss before each and after the last (and 0.5 s more), handed to the service
    in 30 ms blocks at the pace of a microphone."""
    gap = np.zeros(int(gap_s * SAMPLE_RATE))
    x = np.concatenate([p for part in parts for p in (gap, part)] + [gap, np.zeros(SAMPLE_RATE // 2)])
    pcm = to_pcm(x + np.random.default_rng(0).normal(0.0, 10 ** (-70 / 20), x.size))
    assert proc.stdin is not None
    block, start = int(0.03 * SAMPLE_RATE) * 2, time.monotonic()
    for k, at in enumerate(range(0, len(pcm), block)):
        proc.stdin.write(pcm[at : at + block])
        proc.stdin.flush()
        time.sleep(max(0.0, start + (k + 1) * 0.03 - time.monotonic()))


def _word(text: str) -> np.ndarray:
    return np.frombuffer(read_wav(synth.speech_clip(text, "en", 130).path), "<i2") / 32768.0


LONG = ("I saw an X mark 3 seconds ago, and no O since. Show me an O and I will walk. "
        "I saw a triangle 5 seconds ago. I will not walk until I see an O.")
"""Two of the robot's explanations (`reasoner.explain`): about 7 s at the speech service's default rate, so that the
microphone's 3.5 s below end well within it on a busy machine."""


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
@pytest.mark.parametrize("own_voice", ["", "hear"])
def test_the_robot_does_not_answer_its_own_voice(bus: ServiceContext, router_endpoint: str, robot_id: str,
                                                 start_service, tmp_path: Path, own_voice: str) -> None:
    """The real speech service says two long sentences. While it speaks, the microphone (the voice service reading stdin
    at a microphone's pace) hears the sentence's first 1.5 s as the speech service wrote it, then a person's "stop"
    over the rest; once the robot has finished, a "yes". By default the robot's words are not published (a sentence
    that matched no command makes the reasoner say "Sorry, I did not understand.", heard again without end) and
    "stop" and "yes" are; with `HRI_VOICE_OWN_VOICE=hear` the robot's words are published too."""
    states: list[SpeechState] = []
    heard: list[VoiceCommand] = []
    bus.subscribe(bus.keys.speech_state, SpeechState, states.append)
    bus.subscribe(bus.keys.voice_command, VoiceCommand, heard.append)
    say = bus.publisher(bus.keys.speech_say, SpeechRequest)
    out = tmp_path / "said"
    start_service("speech", env={"HRI_SPEECH_OUT": str(out)})
    wait_for(lambda: any(s.id is None for s in states), timeout=20)  # its start-up "not speaking"
    env = service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_VOICE_OWN_VOICE=own_voice)
    with stdin_service(env, tmp_path / "voice.log") as proc:
        expected = "ignored" if own_voice == "" else "heard"
        wait_for(lambda: (h := bus.query_health("voice")) is not None and h.detail.get("own_voice") == expected,
                 timeout=60)
        say.put(SpeechRequest(text=LONG, id="long"))
        wait_for(lambda: any(s.id == "long" and s.speaking for s in states), timeout=10)
        robot = _pcm16k(out / "long.wav")
        assert robot.size > 6.0 * SAMPLE_RATE
        _play(proc, robot[: int(1.5 * SAMPLE_RATE)], _word("stop"))
        assert not any(s.id == "long" and not s.speaking for s in states)  # all of it while the robot spoke
        wait_for(lambda: any(s.id == "long" and not s.speaking for s in states), timeout=10)
        _play(proc, np.zeros(int(TAIL_S * SAMPLE_RATE)), _word("yes"))
        wait_for(lambda: any(m.command is not None and m.command.value == "yes" for m in heard), timeout=20)
        words = [m.command.value if m.command else None for m in heard]
        health = bus.query_health("voice")
        assert health is not None
        log = (tmp_path / "voice.log").read_text()
        if own_voice == "":
            assert words == ["stop", "yes"]
            assert health.detail["own_voice_dropped"] >= 1 and health.detail["own_voice_tail_s"] == TAIL_S
            assert "heard while the robot spoke: not published" in log
        else:
            assert words[-2:] == ["stop", "yes"] and len(words) > 2  # the robot's words, published
            assert health.detail["own_voice_dropped"] == 0 and "not published" not in log


class HeadMicrophone:
    """The robot's microphone in its own head: a faint hiss, what the test says into it, and every sentence the speech
    service says, from the moment it says it (its WAV); handed to the voice service's stdin at a microphone's pace."""

    def __init__(self, proc: subprocess.Popen[bytes], said: Path) -> None:
        self.proc, self.said = proc, said
        self.pending: deque[np.ndarray] = deque()
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def say(self, x: np.ndarray) -> None:
        with self.lock:
            self.pending.append(x)

    def on_state(self, state: SpeechState) -> None:
        if state.speaking and state.id is not None:
            self.say(_pcm16k(self.said / f"{state.id}.wav"))

    def _run(self) -> None:
        assert self.proc.stdin is not None
        rng, block, start = np.random.default_rng(1), int(0.03 * SAMPLE_RATE), time.monotonic()
        sound, k = np.zeros(0), 0
        while not self.stop.is_set():
            if sound.size == 0:
                with self.lock:
                    sound = self.pending.popleft() if self.pending else np.zeros(0)
            x = rng.normal(0.0, 10 ** (-70 / 20), block)
            x[: min(block, sound.size)] += sound[:block]
            sound = sound[block:]
            try:
                self.proc.stdin.write(to_pcm(x))
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError):
                return
            k += 1
            time.sleep(max(0.0, start + k * 0.03 - time.monotonic()))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
@pytest.mark.parametrize("own_voice", ["", "hear"])
def test_a_robot_that_hears_itself_does_not_talk_to_itself(bus: ServiceContext, router_endpoint: str, robot_id: str,
                                                           start_service, tmp_path: Path, own_voice: str) -> None:
    """The reasoner, the speech service and the voice service, its microphone hearing the robot's loudspeaker. A
    person says something that is no command: the robot says "Sorry, I did not understand." once. Told to hear its own
    voice (`HRI_VOICE_OWN_VOICE=hear`), it hears that sentence, does not understand it either, and says so again."""
    decisions: list[Decision] = []
    states: list[SpeechState] = []
    bus.subscribe(bus.keys.reasoner_decision, Decision, decisions.append)
    bus.subscribe(bus.keys.speech_state, SpeechState, states.append)
    said = tmp_path / "said"
    reasoner = start_service("reasoner")
    wait_for(lambda: (h := bus.query_health("reasoner")) is not None and h.detail.get("ready"), timeout=30)
    start_service("speech", env={"HRI_SPEECH_OUT": str(said)})
    wait_for(lambda: any(s.id is None for s in states), timeout=20)
    env = service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_VOICE_OWN_VOICE=own_voice)
    with stdin_service(env, tmp_path / "voice.log") as proc:
        mic = HeadMicrophone(proc, said)
        bus.subscribe(bus.keys.speech_state, SpeechState, mic.on_state)
        try:
            wait_for(lambda: (h := bus.query_health("voice")) is not None and "own_voice" in h.detail, timeout=60)
            mic.say(_word("what a lovely morning"))
            wait_for(lambda: decisions, timeout=20)
            time.sleep(10.0)  # two rounds of the robot's answer, heard and answered, if it hears itself
        finally:
            mic.close()
    assert reasoner.poll() is None
    sorry = [d for d in decisions if d.reason == "not_understood"]
    assert sorry and all(d.say == "Sorry, I did not understand." for d in sorry)
    if own_voice == "":
        assert len(decisions) == 1  # the person's words, answered once
    else:
        assert len(sorry) >= 3  # its own answer, answered again and again
