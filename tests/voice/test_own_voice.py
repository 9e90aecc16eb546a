"""The robot's own voice (`services/voice/own_voice.py`): what the microphone hears while the speech service says the
robot is talking, or just after, is not published, "stop" excepted; recordings are heard as they are."""

from __future__ import annotations

import subprocess
import time
from collections import deque
from collections.abc import Iterator
from contextlib import closing
from pathlib import Path

import numpy as np
import pytest

from schemas.messages import Command, Decision, SpeechRequest, SpeechState, VoiceCommand
from services.runtime import ServiceContext, TypedPublisher
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav
from services.voice.clock import StreamClock
from services.voice.engine import EngineError
from services.voice.own_voice import LONGEST_S, TAIL_S, OwnVoice, OwnVoiceError, tail_from
from services.voice.service import VoiceSettings, check_settings
from services.voice.simmic import PacedMicrophone
from services.voice.sources import stream_utterances
from services.voice.training.tts import wav_samples
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


def test_a_sentence_under_way_at_start_up_is_assumed_until_a_state_says_otherwise() -> None:
    clock = Clock()
    own = OwnVoice(clock=clock)
    clock.now = 105.0
    own.assume(True)  # the speech service's health: speaking, and no state heard since subscribing
    assert own.speaking() and own.overlaps(105.5, 106.0) and not own.overlaps(104.0, 104.9)
    clock.now = 107.0
    own.heard(False)  # the sentence's end
    assert not own.speaking() and own.overlaps(106.5, 107.1) and not own.overlaps(107.5, 108.0)


def test_a_state_heard_before_the_answer_wins_over_it() -> None:
    """The speech service's answer was made before a state that overtook it: the state is newer."""
    clock = Clock()
    own = OwnVoice(clock=clock)
    own.heard(False)  # the sentence ended while the question was on its way back
    own.assume(True)
    assert not own.speaking() and not own.overlaps(0.0, 1e9)
    quiet = OwnVoice(clock=clock)
    quiet.assume(False)
    assert not quiet.speaking()


def test_the_own_voice_bench_counts_what_the_service_would_publish() -> None:
    """`bench/voice_own.py`'s count of commands the service would publish asks `OwnVoice` as the service does: an
    utterance from its speech's onset (`pre_roll_s` into its audio) to when it was cut, "stop" always published."""
    from bench.voice_own import publishes

    yes, stop = Command.YES, Command.STOP
    segs = [(1.9, 1.0, 1.8, yes, 0.9),  # before the robot spoke
            (3.2, 2.5, 3.1, yes, 0.9),  # inside its sentence: its own voice
            (3.2, 2.5, 3.1, stop, 0.9),  # the same, but "stop"
            (4.6, 3.95, 4.5, yes, 0.9),  # its onset (4.2) within the tail after the sentence (to 4.25)
            (4.9, 4.05, 4.8, yes, 0.9),  # its onset (4.3) after the tail
            (2.05, 1.7, 2.0, yes, 0.9)]  # its audio begins before the sentence; its onset (1.95) too, and it was
    #                                      cut (2.05) after the sentence began: it overlaps the voice
    assert publishes(segs, [(2.0, 4.0)], pre_roll_s=0.25) == [True, False, True, False, True, False]
    assert publishes(segs, [], pre_roll_s=0.25) == [True] * 6


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


def test_the_stream_clock_is_the_least_delayed_block_of_the_window() -> None:
    """Blocks of 30 ms captured in real time from t=1000 and read 5 ms later, but for one second in which the listener
    fell 2 s behind and read them in a burst: the capture time of every sample stays right."""
    now = [0.0]
    clock = StreamClock(window_s=10.0, clock=lambda: now[0])
    for k in range(1, 300):  # 9 s of blocks
        lag = 2.0 if 100 <= k < 133 else 0.005
        now[0] = 1000.0 + 0.03 * k + lag
        clock.heard(0.03 * k)
        assert clock.wall(0.03 * k - 0.5) == pytest.approx(1000.0 + 0.03 * k - 0.5 + 0.005)
    assert StreamClock().wall(1.0) is None


def test_the_stream_clock_follows_a_drift_and_starts_again_after_a_gap() -> None:
    now = [0.0]
    clock = StreamClock(window_s=2.0, clock=lambda: now[0])
    for k in range(1, 200):  # a sound card 1 % slow: its stream falls behind the wall clock
        now[0] = 500.0 + 0.03 * k * 1.01
        clock.heard(0.03 * k)
    assert clock.wall(0.03 * 199) == pytest.approx(now[0], abs=0.025)  # not 60 ms off, as from the first block
    now[0] += 30.0  # a paused pipe: nothing read for 30 s, then a block
    clock.heard(0.03 * 200)
    now[0] += 0.03
    clock.heard(0.03 * 201)
    assert clock.wall(0.03 * 201) == pytest.approx(now[0], abs=0.035)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_live_streams_utterance_says_when_its_audio_began() -> None:
    """`Utterance.began`, from the stream's clock: the service places the utterance on the wall clock with it, however
    long the segmenter held it after it ended (the end window, the second VAD's 0.5 s)."""
    pcm = synth.recording([synth.speech_clip(w, "en", 130) for w in ("stop", "yes")], gap_s=1.0)
    t0 = time.time()

    def chunks() -> Iterator[bytes]:  # at a microphone's pace
        for k, at in enumerate(range(0, len(pcm), 960)):
            time.sleep(max(0.0, t0 + (k + 1) * 0.03 - time.time()))
            yield pcm[at : at + 960]

    seen = list(stream_utterances(chunks(), "test"))
    assert len(seen) == 2
    for utt in seen:
        assert utt.start_s is not None and utt.began is not None
        assert utt.began == pytest.approx(t0 + utt.start_s, abs=0.03)
        assert utt.began + utt.seconds <= utt.stamp  # cut once its audio had ended


def _pcm16k(path: Path) -> np.ndarray:
    return wav_samples(path.read_bytes())


def _word(text: str) -> np.ndarray:
    return np.frombuffer(read_wav(synth.speech_clip(text, "en", 130).path), "<i2") / 32768.0


class HeadMicrophone(PacedMicrophone):
    """The robot's microphone in its own head, never silent: a faint hiss, what the test says into it, and (with
    `on_state` subscribed) every sentence the speech service says, from the moment it says it (its WAV)."""

    def __init__(self, proc: subprocess.Popen[bytes], said: Path) -> None:
        self.said = said
        self.pending: deque[np.ndarray] = deque()
        self.playing = 0
        self._sound = np.zeros(0)
        super().__init__(proc)

    def say(self, *parts: np.ndarray, gap_s: float = 0.3) -> None:
        """`parts`, `gap_s` of the hiss between them, after what is already to be said."""
        gap = np.zeros(int(gap_s * SAMPLE_RATE))
        with self.lock:
            self.pending.append(np.concatenate([p for part in parts for p in (part, gap)][:-1]))

    def idle(self) -> bool:
        """Nothing left to say (the hiss goes on)."""
        with self.lock:
            return not self.pending and self.playing == 0

    def on_state(self, state: SpeechState) -> None:
        if state.speaking and state.id is not None:
            self.say(_pcm16k(self.said / f"{state.id}.wav"))

    def sound(self, n: int) -> np.ndarray:
        if self._sound.size == 0 and self.pending:
            self._sound = self.pending.popleft()
        self.playing = self._sound.size
        part, self._sound = self._sound[:n], self._sound[n:]
        return part


def speech_service(bus: ServiceContext, start_service, tmp_path: Path, **env: str
                   ) -> tuple[list[SpeechState], list[VoiceCommand], TypedPublisher[SpeechRequest], Path]:
    """The real speech service writing what it says to `<tmp_path>/said` (`env`: more of its settings), started and
    listening; its states and the voice service's commands as they arrive, and a publisher to make it speak."""
    states: list[SpeechState] = []
    heard: list[VoiceCommand] = []
    bus.subscribe(bus.keys.speech_state, SpeechState, states.append)
    bus.subscribe(bus.keys.voice_command, VoiceCommand, heard.append)
    out = tmp_path / "said"
    start_service("speech", env={"HRI_SPEECH_OUT": str(out), **env})
    wait_for(lambda: any(s.id is None for s in states), timeout=20)  # its start-up "not speaking"
    return states, heard, bus.publisher(bus.keys.speech_say, SpeechRequest), out


LONG = ("I saw an X mark 3 seconds ago, and no O since. Show me an O and I will walk. "
        "I saw a triangle 5 seconds ago. I will not walk until I see an O.")
"""Two of the robot's explanations (`reasoner.explain`): about 7 s at the speech service's default rate, so that the
microphone's 3.5 s below end well within it on a busy machine."""


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
@pytest.mark.parametrize("own_voice", ["", "hear"])
def test_the_robot_does_not_answer_its_own_voice(bus: ServiceContext, router_endpoint: str, robot_id: str,
                                                 start_service, tmp_path: Path, own_voice: str) -> None:
    """The real speech service says two long sentences. While it speaks, the microphone (the voice service reading stdin
    at a microphone's pace) hears their first 1.5 s as the speech service wrote them, then a person's "stop" over the
    rest; once the robot has finished, a "yes". By default the robot's words are not published (a sentence
    that matched no command makes the reasoner say "Sorry, I did not understand.", heard again without end) and
    "stop" and "yes" are; with `HRI_VOICE_OWN_VOICE=hear` the robot's words are published too. The echo canceller is
    off: this microphone stops hearing the robot after 1.5 s while the robot goes on speaking, and what the canceller
    makes of that depends on whether it found the echo, which a loaded machine decides (a render slowed by 0.5 s turned
    a lost echo into a found one, and the robot's 1.5 s and the "stop" into one utterance, stop 105); its own tests are
    in `test_echo.py`."""
    states, heard, say, out = speech_service(bus, start_service, tmp_path)
    env = service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_VOICE_OWN_VOICE=own_voice,
                      HRI_VOICE_ECHO_CANCEL="off", HRI_STATE_DIR=str(tmp_path / "state"))
    with stdin_service(env, tmp_path / "voice.log") as proc, closing(HeadMicrophone(proc, out)) as mic:
        expected = "ignored" if own_voice == "" else "heard"
        wait_for(lambda: (h := bus.query_health("voice")) is not None and h.detail.get("own_voice") == expected,
                 timeout=60)
        say.put(SpeechRequest(text=LONG, id="long"))
        wait_for(lambda: any(s.id == "long" and s.speaking for s in states), timeout=10)
        robot = _pcm16k(out / "long.wav")
        assert robot.size > 6.0 * SAMPLE_RATE
        mic.say(robot[: int(1.5 * SAMPLE_RATE)], _word("stop"))
        wait_for(mic.idle, timeout=10)
        assert not any(s.id == "long" and not s.speaking for s in states)  # all of it while the robot spoke
        wait_for(lambda: any(s.id == "long" and not s.speaking for s in states), timeout=15)
        mic.say(np.zeros(int(TAIL_S * SAMPLE_RATE)), _word("yes"))
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


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_sentence_under_way_when_the_voice_service_starts_is_the_robots(bus: ServiceContext, router_endpoint: str,
                                                                         robot_id: str, start_service,
                                                                         tmp_path: Path) -> None:
    """The speech service is in the middle of a long sentence, its `speaking=True` long sent, when the voice service
    starts. Asked at start-up, the speech service's health says it is speaking: what the microphone hears of the
    sentence is not published; a person's "stop" over it is, and a "yes" once it has ended."""
    states, heard, say, out = speech_service(bus, start_service, tmp_path, HRI_SPEECH_RATE="110")
    say.put(SpeechRequest(text=f"{LONG} {LONG}", id="long"))  # about 20 s at 110 words a minute
    wait_for(lambda: any(s.id == "long" and s.speaking for s in states), timeout=10)
    robot = _pcm16k(out / "long.wav")
    assert robot.size > 15.0 * SAMPLE_RATE
    env = service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_STATE_DIR=str(tmp_path / "state"))
    with stdin_service(env, tmp_path / "voice.log") as proc, closing(HeadMicrophone(proc, out)) as mic:
        # the engine ready (its embedding in health) and the question answered
        wait_for(lambda: (h := bus.query_health("voice")) is not None and "spotter_embedding" in h.detail
                 and "own_voice_asked" in h.detail, timeout=60)
        health = bus.query_health("voice")
        assert health is not None and health.detail["own_voice_asked"] == "speaking"
        ended = lambda: any(s.id == "long" and not s.speaking for s in states)  # noqa: E731
        assert not ended(), "the voice service took the whole sentence to start: too slow a machine for this test"
        mic.say(robot[int(8.0 * SAMPLE_RATE) : int(10.0 * SAMPLE_RATE)], _word("stop"))
        wait_for(mic.idle, timeout=10)
        assert not ended()
        wait_for(ended, timeout=40)
        mic.say(np.zeros(int(TAIL_S * SAMPLE_RATE)), _word("yes"))
        wait_for(lambda: any(m.command is not None and m.command.value == "yes" for m in heard), timeout=20)
    assert [m.command.value if m.command else None for m in heard] == ["stop", "yes"]
    assert "heard while the robot spoke: not published" in (tmp_path / "voice.log").read_text()


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
    env = service_env(router_endpoint, robot_id, HRI_VOICE_SOURCE="stdin", HRI_VOICE_OWN_VOICE=own_voice,
                      HRI_STATE_DIR=str(tmp_path / "state"))
    with stdin_service(env, tmp_path / "voice.log") as proc, closing(HeadMicrophone(proc, said)) as mic:
        bus.subscribe(bus.keys.speech_state, SpeechState, mic.on_state)
        wait_for(lambda: (h := bus.query_health("voice")) is not None and "own_voice" in h.detail, timeout=60)
        mic.say(_word("what a lovely morning"))
        wait_for(lambda: decisions, timeout=20)
        time.sleep(10.0)  # several rounds of the robot's answer, heard and answered, if it hears itself
    assert reasoner.poll() is None
    sorry = [d for d in decisions if d.reason == "not_understood"]
    assert sorry and all(d.say == "Sorry, I did not understand." for d in sorry)
    if own_voice == "":
        assert len(decisions) == 1  # the person's words, answered once
    else:
        assert len(sorry) >= 3  # its own answer, answered again and again
