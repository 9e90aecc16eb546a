"""What the robot hears of its own voice (prints figures; not a test).

On the OP2 the loudspeaker and the microphones are in the same head. Every sentence the robot says ("Sorry, I cannot
do it.", "Shall I walk forward?", the answers to "why") reaches its own microphone a few centimetres away, louder
than any person. This bench says what the voice service would make of it: each sentence the reasoner can say (the
agent's spoken strings, `services/reasoner/agent/*.soar`, and every explanation, `reasoner.explain.TEMPLATES`, filled
with each command word and mark) is synthesised by the speech service's own engine and settings (espeak-ng, its
default voice, rate and volume), brought to each `--peaks` level (dBFS peak at the microphone), placed in a quiet
room's hiss and fed to the service's stream path (`Segmenter` in 30 ms chunks, then the engine), with the robot's
speech state ignored: as the service would hear it if it did not know the robot was talking (`HRI_VOICE_OWN_VOICE=hear`;
by default it publishes none of it but "stop", `services/voice/own_voice.py`).

`--room`: each sentence through a room drawn as in `voice_room.py` (its reverberation time from `--rt60`), the
loudspeaker 0.1 m from the microphone; the rows then also say how late after the robot's voice ended an utterance
began (the echo), against the service's tail (`own_voice.TAIL_S`).

`--over SEED`: a person's "stop" said over the robot's voice, the one word the service still publishes then: the clean
held-out "stop"s of `voice_bench`'s seed (other voices and engines), each placed at a random moment within one of the
sentences, peaking at `--person` dBFS (-26: a person about a metre away), against the same "stop"s with no robot
voice under them. A "stop" counts when an utterance that overlaps it is heard as "stop".

`--cancel` (with `--over`): the service's echo canceller (`services/voice/echo.py`). Each "stop" is said over the last
of `--warm` + 1 of the robot's sentences in a row (4 by default; `--warm 0`: a canceller that has not heard the robot
before), through an `EchoPath` drawn for it (a room with the loudspeaker 0.1 m away, a small loudspeaker's soft
clipping, the sound card's delay and the state's error per sentence); the same streams are heard each of `WAYS`:
without the canceller, with it cancelling each sentence once its echo is found, held back meanwhile and cancelled from
the sentence's first sample (`look_back`), with what was held also learnt from first (`learn_first`), and that with
the way fitted on the canceller's memory subtracted first (`fit`: the service's default), with how many of the "stop"s
began within 0.6 s of their sentence's echo and how many of those each way heard (`--way`: only the ways named), and
how many utterances not over the person's word each way heard as a command, and how many of those the service would
publish (its own-voice gate, `own_voice.OwnVoice`, asked with the sentences' states: "stop" always, any other command
only outside the robot's voice and `own_voice.TAIL_S` after). `--after`: each "stop" said 0-0.3 s after the last
sentence's echo ends instead. The segmenter is told where the canceller says the robot's voice lies, as in the service
(`SegmenterConfig.floor_hold`, `floor_hold_after`: since stop 96 held and trusted once the robot's voice has passed;
`--floor-hold on`: held throughout, `off`: not held). The sentences are taken in turn from the list
(the same ones whatever the held-out seed); `--draw-sentences`: drawn at random from `--seed` for each "stop".
`--cancel-only`: only these rows. Each row also says how many of the person's "stop"s the service would publish, and
what `HRI_VOICE_OWN_STOP=ignore` (`--own-stop`; the service's default otherwise) keeps back: a "stop" whose speech
began at the robot's own "stop" (espeak-ng's word events, placed where the canceller found the sentence's echo,
`own_voice.said_stop`), the person's and the stray ones counted apart (`own_stop_dropped`), and where each "stop"
heard over such a sentence began against the robot's own (`own_stop_onsets`).

`--recall` (with `--over`): each "stop" said over the robot's first sentence of a run (the voice service just started),
through an `EchoPath` drawn for it; the same streams heard each of `RECALLS`: without the canceller, with the service's
canceller cold, and with one that first recalled what an earlier run's canceller remembered of three other sentences
(`EchoCanceller.memory`, `recall`; the service keeps it in the state folder), heard through another room with the
same loudspeaker (the robot carried elsewhere) or through the same room.

Per level: sentences heard as speech at all (each such utterance is a `VoiceCommand`; one that matched no command
makes the reasoner answer "Sorry, I did not understand.", which the microphone hears again), sentences heard as a
command (which ones, and those the reasoner would act on), and "go"s that would walk the robot or make it ask.

    .venv/bin/python bench/voice_own.py
    .venv/bin/python bench/voice_own.py --peaks -20 --mic-rate 48000 --json out.json
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.signal import fftconvolve

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import ASK, WALK, WORDS, Policy, heldout_items, through_mic  # noqa: E402
from bench.voice_levels import at_level, in_room  # noqa: E402
from bench.voice_room import Room, draw_room, responses, rt60_range  # noqa: E402
from bench.voice_walking import LEAD_S, stream  # noqa: E402
from schemas.messages import Command  # noqa: E402
from services.reasoner.explain import MARK_NAMES, TEMPLATES  # noqa: E402
from services.reasoner.explain import WORDS as EXPLAINED_WORDS  # noqa: E402
from services.speech.config import DEFAULT_RATE, DEFAULT_VOICE, DEFAULT_VOLUME  # noqa: E402
from services.speech.tts import EspeakNg  # noqa: E402
from services.voice.audio import SAMPLE_RATE, rounded_pcm  # noqa: E402
from services.voice.echo import LOCK_S, SEARCH_S, EchoCanceller, Played, Sentence  # noqa: E402
from services.voice.engine import Engine, make_engine  # noqa: E402
from services.voice.espeak_words import words  # noqa: E402
from services.voice.mic import CHUNK_S  # noqa: E402
from services.voice.own_voice import OWN_STOP_DEFAULT, TAIL_S, OwnVoice, own_stop_from, said_stop  # noqa: E402
from services.voice.robot_voice import speech_end_s, stop_words  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402
from services.voice.training.tts import wav_samples  # noqa: E402

AGENT = ROOT / "services" / "reasoner" / "agent"


def agent_sentences(folder: Path = AGENT) -> list[str]:
    """The sentences written into the Soar agent (`|...|` strings with a space, ending in . ? or !)."""
    found = {m for path in sorted(folder.glob("*.soar")) for m in re.findall(r"\|([^|]+ [^|]+[.?!])\|", path.read_text())}
    return sorted(found)


def explanation_sentences() -> list[str]:
    """Every explanation, filled as `reasoner.explain.render` fills it: with each command word (after "told me to",
    as the robot reads it), each mark or "a danger sign", and "just now" or "3 seconds ago"."""
    out: set[str] = set()
    for name, template in TEMPLATES.items():
        for word in (*WORDS, "that"):
            for mark in (*MARK_NAMES.values(), "a danger sign"):
                for ago in ("just now", "3 seconds ago"):
                    out.add(template.format(word=EXPLAINED_WORDS.get(word, word) if name == "obeyed" else word,
                                            mark=mark, ago=ago, cause_ago=ago))
        out.update(f"I was not sure I heard '{word}'." for word in WORDS)
    return sorted(out)


def spoken(text: str, engine: EspeakNg, folder: Path) -> np.ndarray:
    """`text` as the speech service says it, at 16 kHz (float, ±1)."""
    path = folder / "say.wav"
    engine.synthesize(text, path)
    return wav_samples(path.read_bytes())


def own_room(rng: np.random.Generator, rt60: tuple[float, float]) -> Room:
    """A room drawn as `voice_room.draw_room` draws one, the robot's loudspeaker 0.1 m from its microphone."""
    room = draw_room(rng, [1.0], rt60)
    x, y, z = room.mic
    return Room(room.size, room.rt60, room.mic, ((x + 0.1, y, z),))


def stop_over_voice(engine: Engine, config: SegmenterConfig, voices: list[np.ndarray], stops: list[np.ndarray],
                    peak: float | None, person: float, floor: float, mic_rate: int | None,
                    rng: np.random.Generator) -> int:
    """How many of `stops` (at `person` dBFS peak) are heard as "stop" said over the robot's voices (at `peak` dBFS
    peak, in turn; None: no robot voice)."""
    heard = 0
    for k, stop in enumerate(stops):
        stop = at_level(stop, person)
        voice = voices[k % len(voices)]
        voice = at_level(voice, peak) if peak is not None else np.zeros_like(voice)
        at = int(rng.uniform(0.2, max(0.3, voice.size / SAMPLE_RATE - 0.3)) * SAMPLE_RATE)
        x = np.zeros(max(voice.size, at + stop.size))
        x[: voice.size] += voice
        x[at : at + stop.size] += stop
        segs = stream(engine, through_mic(np.clip(in_room(x, floor, rng), -1.0, 1.0), mic_rate), config)
        begin, end = LEAD_S + at / SAMPLE_RATE, LEAD_S + (at + stop.size) / SAMPLE_RATE
        heard += any(cmd is Command.STOP and s < end and e > begin for _, s, e, cmd, _ in segs)
    return heard


@dataclass
class EchoPath:
    """The way from the robot's loudspeaker to its microphone, for `--cancel`: a room with the loudspeaker 0.1 m away
    (`own_room`), a small loudspeaker's soft clipping (`tanh`, its drive), and per sentence the sound card's delay
    (20-60 ms) and how late or early the speech service's state says it began (±30 ms: the bus, the player's start)."""

    response: np.ndarray
    drive: float

    @classmethod
    def draw(cls, rng: np.random.Generator, rt60: tuple[float, float]) -> EchoPath:
        return cls(responses(own_room(rng, rt60))[0], float(rng.uniform(0.5, 2.0)))

    def echo(self, voice: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, float]:
        """The sentence as the microphone hears it (unscaled), and the state's error, s."""
        delay = np.zeros(int(rng.uniform(0.02, 0.06) * SAMPLE_RATE))
        return fftconvolve(np.concatenate([delay, self._bent(voice)]), self.response), float(rng.uniform(-0.03, 0.03))

    def peak(self, voice: np.ndarray) -> float:
        """The peak of `echo(voice)` (which the sound card's delay does not change)."""
        return float(np.max(np.abs(fftconvolve(self._bent(voice), self.response))))

    def _bent(self, voice: np.ndarray) -> np.ndarray:
        return np.tanh(self.drive * 0.5 * voice) / np.tanh(self.drive)


EARLY_S = LOCK_S + SEARCH_S[1]
"""A "stop" begun this soon after its sentence's echo (or before) is within what the canceller holds back while it
looks for that echo (`EchoCanceller.look_back`); without the look-back it is not cancelled."""


WAYS: dict[str, dict[str, bool] | None] = {
    "without": None,
    "once found": {"look_back": False, "learn_first": False, "fit": False},
    "held back": {"look_back": True, "learn_first": False, "fit": False},
    "learnt first": {"look_back": True, "learn_first": True, "fit": False},
    "learnt first, fitted": {"look_back": True, "learn_first": True, "fit": True},
}
"""`--cancel`'s ways of hearing each stream: without the canceller; with it cancelling each sentence once its echo is
found (round voice45); held back meanwhile and cancelled from the sentence's first sample (round voice46); the held
samples also learnt from before they are cancelled (rounds voice47 and 47b); and that with the way fitted on the
canceller's memory subtracted first (`EchoCanceller.fit`, round voice49: the service's default). Each way names every
setting it differs in: one left to the canceller's default would follow the default when it changes (as "learnt
first" did from stop 89 to stop 90, fitted like the last way; seed 22171 was measured so and run again)."""


@dataclass
class OverEcho:
    """`--cancel`'s "stop"s heard over the robot's voice, each of `WAYS`; `early`: those begun within `EARLY_S` of
    their sentence's echo, and how many of them each way heard."""

    stops: int = 0
    heard: Counter[str] = field(default_factory=Counter)
    early: int = 0
    early_heard: Counter[str] = field(default_factory=Counter)
    stray: Counter[str] = field(default_factory=Counter)
    """Utterances heard as a command that do not overlap the person's "stop" (`--cancel`): what is left of the robot's
    voice taken for a word."""
    stray_at: dict[str, list[tuple[str, float]]] = field(default_factory=dict)
    """Each of those: the command, and where the utterance ends against the end of the last sentence's echo (s, 30 dB
    under its loudest). The service publishes no command but "stop" heard while the robot speaks or within
    `own_voice.TAIL_S` after (`own_voice.py`); `stray` counts them all, `published` only those it would publish
    (`publishes`)."""
    published: Counter[str] = field(default_factory=Counter)
    """Of `stray`, those the service's own-voice gate would publish."""
    published_at: dict[str, list[tuple[str, float]]] = field(default_factory=dict)
    heard_published: Counter[str] = field(default_factory=Counter)
    """Of `heard`, the "stop"s the service would publish (with `HRI_VOICE_OWN_STOP=ignore`, not one that began where
    the robot itself said "stop", `own_voice.said_stop`)."""
    own_stop_dropped: dict[str, Counter[str]] = field(default_factory=dict)
    """What that gate kept from being published: the person's "stop"s ("person": heard, but only in utterances it
    dropped) and stray "stop"s ("stray"). With it off (`hear`), none; the figures with it off are those with it on
    plus these."""
    own_stop_onsets: dict[str, list[tuple[str, float, float]]] = field(default_factory=dict)
    """Each "stop" heard over a sentence in which the robot says "stop" (the person's, "person", or another, "stray"):
    where its speech began against the robot's own nearest "stop" in the stream (s after its beginning, after its
    end), as the canceller placed the sentence."""


def publishes(segs: list[tuple[float, float, float, Command | None, float]], spoke: list[tuple[float, float]],
              pre_roll_s: float, tail_s: float = TAIL_S, placed: list[Sentence] | None = None,
              t0: float = 0.0) -> list[bool]:
    """For each of `stream`'s segments, whether the voice service would publish it with the robot speaking in the
    spans `spoke` (stream seconds, as its speech states say): the service's own `OwnVoice` asked as the service asks
    it (the utterance from its speech's onset, `pre_roll_s` into its audio, to when it was cut), "stop" always; with
    `placed` (the canceller's sentences, their echoes found on the wall clock `t0` + stream seconds: the service with
    `HRI_VOICE_OWN_STOP=ignore`), a "stop" only where it did not begin at the robot's own (`own_voice.said_stop`)."""
    now = [0.0]
    own = OwnVoice(tail_s, clock=lambda: now[0])
    for begin, end in sorted(spoke):
        now[0] = begin
        own.heard(True)
        now[0] = end
        own.heard(False)
    return [(placed is None or not said_stop(placed, t0 + min(start + pre_roll_s, cut))) if cmd is Command.STOP
            else not own.overlaps(min(start + pre_roll_s, cut), cut) for cut, start, _, cmd, _ in segs]


def own_stop_onsets(segs: list[tuple[float, float, float, Command | None, float]], over: list[bool],
                    placed: list[Sentence], pre_roll_s: float, t0: float) -> list[tuple[str, float, float]]:
    """`OverEcho.own_stop_onsets` of one stream."""
    words = [(s.heard_at + a - t0, s.heard_at + b - t0) for s in placed if s.heard_at is not None for a, b in s.stops]
    out = []
    for (cut, start, _, cmd, _), o in zip(segs, over, strict=True):
        if cmd is Command.STOP and words:
            onset = min(start + pre_roll_s, cut)
            a, b = min(words, key=lambda w: abs(onset - w[0]))
            out.append(("person" if o else "stray", round(onset - a, 3), round(onset - b, 3)))
    return out


def stop_over_cancelled(engine: Engine, config: SegmenterConfig, voices: list[np.ndarray], stops: list[np.ndarray],
                        peak: float, person: float, floor: float, mic_rate: int | None, rt60: tuple[float, float],
                        rng: np.random.Generator, warm: int = 3, ways: list[str] | None = None,
                        after: bool = False, draw: bool = False,
                        stops_said: list[tuple[tuple[float, float], ...]] | None = None,
                        own_stop: bool = OWN_STOP_DEFAULT == "ignore", memory_seed: int | None = None) -> OverEcho:
    """`--cancel`: each of `stops` said over the last of `warm` + 1 sentences the robot says in a row (0.3 s apart)
    through an `EchoPath` drawn for it, the last at `peak` dBFS peak at the microphone (`after`: said 0-0.3 s after
    that sentence's echo ends, at its last sample within 30 dB of its loudest sample; `voice_stop_latency.py` places
    its gaps the same 0-0.3 s after an end found per 10 ms frame, `voice_bench.speech_end_s`); the stream (through the
    microphone's path at `mic_rate`) to the service's `EchoCanceller`, the sentences placed where their (jittered)
    states say, 30 ms at a time, then to the segmenter and the engine. How many "stop"s each of `ways` (of `WAYS`; all
    by default) hears (`OverEcho`), on the same streams. The sentences are taken in turn, the `k`th "stop"'s from the
    `k`th on; `draw`: drawn at random (`rng`) for each "stop". `stops_said`: when the robot says "stop" in each of
    `voices` (`robot_voice.stop_words`), as the service knows it; `own_stop`: the service's `HRI_VOICE_OWN_STOP=ignore`
    (a "stop" that begins at the robot's own is not published), with `stops_said`. `memory_seed`: each stream's
    canceller first recalls what one remembered of three other sentences through the same room and loudspeaker
    (`echo_memory`), drawn from this seed and the stream's number, so the streams are those without it: the service
    after its first run (its memory kept in the state folder, round voice48); None: the canceller starts cold."""
    out = OverEcho()
    gap, t0 = int(0.3 * SAMPLE_RATE), 1000.0
    for k, stop in enumerate(stops):
        path = EchoPath.draw(rng, rt60)
        if draw:
            picked = [int(i) for i in rng.choice(len(voices), warm + 1, replace=False)]
        else:
            picked = [(k + j) % len(voices) for j in range(warm, -1, -1)]
        said = [voices[i] for i in picked]
        echoes = [path.echo(v, rng) for v in said]
        scale = 10 ** (peak / 20) / (np.max(np.abs(echoes[-1][0])) + 1e-12)
        memory = None
        if memory_seed is not None:
            drawn = np.random.default_rng((memory_seed, k))
            rest = [i for i in range(len(voices)) if i not in picked]
            earlier = drawn.choice(rest, min(3, len(rest)), replace=False)
            memory = echo_memory([voices[i] for i in earlier], path, scale, floor, mic_rate, drawn, t0)
        starts = np.cumsum([int(LEAD_S * SAMPLE_RATE)] + [e.size + gap for e, _ in echoes[:-1]])
        x = rng.normal(0.0, 10 ** (floor / 20), int(starts[-1]) + echoes[-1][0].size + (2 if after else 1) * SAMPLE_RATE)
        played = []  # each sentence as its (jittered) state says it began
        for start, (echo, late), voice in zip(starts, echoes, said, strict=True):
            x[start : start + echo.size] += echo * scale
            played.append((t0 + start / SAMPLE_RATE + late, voice))
        spoke = [(began - t0, began - t0 + voice.size / SAMPLE_RATE) for began, voice in played]
        last = int(starts[-1])
        loud = np.abs(echoes[-1][0]) > 10 ** (-30 / 20) * np.max(np.abs(echoes[-1][0]))
        echo_ends = last + int(np.flatnonzero(loud)[-1])
        if after:
            at = echo_ends + int(rng.uniform(0.0, 0.3) * SAMPLE_RATE)
        else:
            at = last + int(rng.uniform(0.2, max(0.3, said[-1].size / SAMPLE_RATE - 0.3)) * SAMPLE_RATE)
        stop = at_level(stop, person)
        x[at : at + stop.size] += stop
        x = through_mic(np.clip(x, -1.0, 1.0), mic_rate)
        pcm, block = rounded_pcm(x), 2 * int(CHUNK_S * SAMPLE_RATE)
        echo_begins = last + int(np.argmax(np.abs(echoes[-1][0]) > 1e-3 * np.max(np.abs(echoes[-1][0]))))
        early = at - echo_begins < EARLY_S * SAMPLE_RATE
        out.stops += 1
        out.early += early
        for way in ways or list(WAYS):
            settings, placed = WAYS[way], Played()
            for (began, voice), i in zip(played, picked, strict=True):
                placed.add(began, voice).stops = stops_said[i] if stops_said is not None else ()
            z, near = (x, None) if settings is None else _cancelled(placed, settings, pcm, block, t0, memory)
            segs = stream(engine, z, config, robot=near)
            over = [s < (at + stop.size) / SAMPLE_RATE and e > at / SAMPLE_RATE for _, s, e, _, _ in segs]
            gate = publishes(segs, spoke, config.pre_roll_s, placed=placed.sentences() if own_stop else None, t0=t0)
            heard = any(cmd is Command.STOP and o for (*_, cmd, _), o in zip(segs, over, strict=True))
            published = any(cmd is Command.STOP and o and p
                            for (*_, cmd, _), o, p in zip(segs, over, gate, strict=True))
            out.heard_published[way] += published
            dropped = out.own_stop_dropped.setdefault(way, Counter())
            dropped["person"] += heard and not published
            dropped["stray"] += sum(cmd is Command.STOP and not o and not p
                                    for (*_, cmd, _), o, p in zip(segs, over, gate, strict=True))
            out.own_stop_onsets.setdefault(way, []).extend(
                own_stop_onsets(segs, over, placed.sentences(), config.pre_roll_s, t0))
            stray = [((cmd.value, round(e - echo_ends / SAMPLE_RATE, 2)), p)
                     for (_, _, e, cmd, _), o, p in zip(segs, over, gate, strict=True) if cmd is not None and not o]
            out.stray[way] += len(stray)
            out.stray_at.setdefault(way, []).extend(at for at, _ in stray)
            out.published[way] += sum(p for _, p in stray)
            out.published_at.setdefault(way, []).extend(at for at, p in stray if p)
            out.heard[way] += heard
            out.early_heard[way] += heard and early
    return out


RECALLS = ("without", "cold", "recalled, another room", "recalled, same room", "fitted, another room",
           "fitted, same room")
"""`--recall`'s ways of hearing each stream: without the canceller; with a canceller that has not heard the robot (the
service just started); with one that first `recall`ed what an earlier run's canceller remembered of three sentences
(`EchoCanceller.memory`), heard through another room (the same head's loudspeaker at the same volume) or the same one;
and the same with the way fitted on that memory subtracted first (`EchoCanceller.fit`, round voice49). (Until round
voice49 each memory was made at the level of its own loudest sentence, not at the run's volume: a level mismatch of a
dB or two that a recording of the same loudspeaker does not have.)"""


def stop_over_recalled(engine: Engine, config: SegmenterConfig, voices: list[np.ndarray], stops: list[np.ndarray],
                       peak: float, person: float, floor: float, mic_rate: int | None, rt60: tuple[float, float],
                       rng: np.random.Generator, before: int = 3) -> OverEcho:
    """`--recall`: each of `stops` said over the robot's first sentence of a run, through an `EchoPath` drawn for it;
    the canceller (the service's defaults) cold, or having recalled the memory of an earlier run in which the robot
    said `before` other sentences, through another room with the same loudspeaker, or through the same room. How
    many "stop"s each of `RECALLS` hears, on the same streams."""
    out = OverEcho()
    t0 = 1000.0
    for k, stop in enumerate(stops):
        path = EchoPath.draw(rng, rt60)
        elsewhere = EchoPath(responses(own_room(rng, rt60))[0], path.drive)
        earlier = [voices[(k + 1 + j) % len(voices)] for j in range(before)]
        voice = voices[k % len(voices)]
        scale = 10 ** (peak / 20) / (path.peak(voice) + 1e-12)
        memories = {way: echo_memory(earlier, room, scale, floor, mic_rate, rng, t0)
                    for way, room in (("recalled, another room", elsewhere), ("recalled, same room", path))}
        echo, late = path.echo(voice, rng)
        start = int(LEAD_S * SAMPLE_RATE)
        x = rng.normal(0.0, 10 ** (floor / 20), start + echo.size + SAMPLE_RATE)
        x[start : start + echo.size] += echo * scale
        at = start + int(rng.uniform(0.2, max(0.3, voice.size / SAMPLE_RATE - 0.3)) * SAMPLE_RATE)
        stop = at_level(stop, person)
        x[at : at + stop.size] += stop
        x = through_mic(np.clip(x, -1.0, 1.0), mic_rate)
        pcm, block = rounded_pcm(x), 2 * int(CHUNK_S * SAMPLE_RATE)
        echo_begins = start + int(np.argmax(np.abs(echo) > 1e-3 * np.max(np.abs(echo))))
        early = at - echo_begins < EARLY_S * SAMPLE_RATE
        out.stops += 1
        out.early += early
        said = [(t0 + start / SAMPLE_RATE + late, voice)]
        for way in RECALLS:
            fitted = way.startswith("fitted")
            recall = memories.get(way.replace("fitted", "recalled"))
            z, near = (x, None) if way == "without" else _cancelled(said, {"fit": fitted}, pcm, block, t0, recall)
            heard = any(cmd is Command.STOP and s < (at + stop.size) / SAMPLE_RATE and e > at / SAMPLE_RATE
                        for _, s, e, cmd, _ in stream(engine, z, config, robot=near))
            out.heard[way] += heard
            out.early_heard[way] += heard and early
    return out


def echo_memory(said: list[np.ndarray], path: EchoPath, scale: float, floor: float, mic_rate: int | None,
                rng: np.random.Generator, t0: float) -> tuple[np.ndarray, np.ndarray]:
    """What a canceller (the service's defaults) remembers (`EchoCanceller.memory`) after the robot said the sentences
    `said`, 0.3 s apart, through `path` at the loudspeaker's volume `scale` (the run's: the volume does not change from
    run to run), in a quiet room."""
    gap = int(0.3 * SAMPLE_RATE)
    echoes = [path.echo(v, rng) for v in said]
    starts = np.cumsum([int(LEAD_S * SAMPLE_RATE)] + [e.size + gap for e, _ in echoes[:-1]])
    x = rng.normal(0.0, 10 ** (floor / 20), int(starts[-1]) + echoes[-1][0].size + SAMPLE_RATE)
    played = Played()
    for start, (echo, late), voice in zip(starts, echoes, said, strict=True):
        x[start : start + echo.size] += echo * scale
        played.add(t0 + start / SAMPLE_RATE + late, voice)
    pcm, block = rounded_pcm(through_mic(np.clip(x, -1.0, 1.0), mic_rate)), 2 * int(CHUNK_S * SAMPLE_RATE)
    canceller = EchoCanceller(played)
    for i in range(0, len(pcm), block):
        canceller(pcm[i : i + block], t0 + i / 2 / SAMPLE_RATE)
    return canceller.memory()


def _cancelled(said: list[tuple[float, np.ndarray]] | Played, settings: dict[str, bool], pcm: bytes, block: int,
               t0: float, recall: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """`pcm` through a new `EchoCanceller` (with `settings`; first `recall`ing a memory, if given) told of the sentences
    `said` (when each began, its samples; or a `Played` holding them, in which the canceller then places them), in the
    microphone's blocks (what it holds at the end passed on), and per sample whether the canceller said the robot's
    voice lay in the chunk it passed it on in (`robot_near`: the segmenter holds its floor there, as in the
    service)."""
    played = said if isinstance(said, Played) else Played()
    for began, samples in [] if isinstance(said, Played) else said:
        played.add(began, samples)
    canceller = EchoCanceller(played, **settings)
    if recall is not None:
        canceller.recall(*recall)
    out, near = [], []
    for i in range(0, len(pcm) + block, block):  # the last call (the stream's end) passes on what was held
        y = canceller(pcm[i : i + block], t0 + i / 2 / SAMPLE_RATE) if i < len(pcm) else canceller(b"", None)
        out.append(y)
        near.append(np.full(len(y) // 2, canceller.robot_near))
    return np.frombuffer(b"".join(out), "<i2") / 32768.0, np.concatenate(near)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engine", default="spotter")
    ap.add_argument("--peaks", default="-26,-12,-3", help="the robot's voice at its own microphone, dBFS peak")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss through the microphone, dBFS RMS")
    ap.add_argument("--mic-rate", type=int, help="through a microphone at this rate, resampled by the service")
    ap.add_argument("--seed", type=int, default=1, help="seed of the hiss and the rooms")
    ap.add_argument("--room", action="store_true", help="each sentence through a room, the loudspeaker 0.1 m away")
    ap.add_argument("--rt60", default="0.25,0.6", help="with --room: the reverberation time's range (Sabine), s")
    ap.add_argument("--over", type=int, help="voice_bench's held-out seed: its people's \"stop\" said over the robot")
    ap.add_argument("--person", type=float, default=-26.0, help="with --over: the person's \"stop\", dBFS peak")
    ap.add_argument("--cancel", action="store_true",
                    help="with --over: the robot's voice through a room and a small loudspeaker, --warm sentences "
                         "before the one the \"stop\" is said over, with and without the service's echo canceller")
    ap.add_argument("--warm", type=int, default=3,
                    help="with --cancel: the robot's sentences before the one the \"stop\" is said over (0: the "
                         "canceller has not heard the robot before, as when the voice service has just started)")
    ap.add_argument("--way", action="append", choices=list(WAYS),
                    help="with --cancel: hear the streams this way only (repeatable; all of WAYS by default)")
    ap.add_argument("--recall", action="store_true",
                    help="with --over: the \"stop\"s said over the robot's first sentence of a run, the canceller "
                         "cold or recalling an earlier run's memory of the robot's voice (another room, the same one)")
    ap.add_argument("--after", action="store_true",
                    help="with --cancel: each \"stop\" said 0-0.3 s after the sentence's echo ends, not over it")
    ap.add_argument("--draw-sentences", action="store_true",
                    help="with --cancel: the robot's sentences before and under each \"stop\" drawn at random from "
                         "--seed, not taken in turn (two held-out seeds then hear other sentences)")
    ap.add_argument("--cancel-only", action="store_true",
                    help="with --cancel: only the echo canceller's rows (not the sentences heard one by one, nor the "
                         "\"stop\"s over the robot's voice with no room)")
    ap.add_argument("--floor-hold", choices=("on", "off", "after"),
                    help="with --cancel: the segmenter's noise floor held where the canceller says the robot's voice "
                         "lies, or not, or held but judging an utterance only once the robot's voice has passed "
                         "(SegmenterConfig.floor_hold, floor_hold_after; default: the service's)")
    ap.add_argument("--memory", action="store_true",
                    help="with --cancel: each stream's canceller first recalls its memory of three other sentences "
                         "through the same room, as the service does after its first run (the same streams)")
    ap.add_argument("--own-stop", choices=("ignore", "hear"),
                    help="with --cancel: a \"stop\" that begins where the robot itself says \"stop\" is not "
                         "published (ignore), or is (hear) (HRI_VOICE_OWN_STOP; default: the service's)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    try:
        rt60 = rt60_range(args.rt60)
    except ValueError as exc:
        ap.error(str(exc))
    if args.cancel_only and not (args.over is not None and args.cancel):
        ap.error("--cancel-only needs --over and --cancel")
    ways = args.way or list(WAYS)
    sentences = agent_sentences() + explanation_sentences()
    tts = EspeakNg(DEFAULT_VOICE, DEFAULT_RATE, DEFAULT_VOLUME)
    with tempfile.TemporaryDirectory(prefix="hri-own-voice-") as tmp:
        voices = [spoken(s, tts, Path(tmp)) for s in sentences]
    dry = list(voices)
    # when the robot says "stop" in each sentence, as the service finds it (espeak-ng's word events)
    stops_said = [stop_words(text, words(text, DEFAULT_VOICE, DEFAULT_RATE), speech_end_s(v))
                  for text, v in zip(sentences, dry, strict=True)]
    ends = [LEAD_S + v.size / SAMPLE_RATE for v in voices]  # where the loudspeaker falls silent, stream seconds
    if args.room:
        rng = np.random.default_rng(args.seed)
        voices = [fftconvolve(v, responses(own_room(rng, rt60))[0]) for v in voices]
    engine, policy = make_engine(args.engine), Policy.from_knowledge()
    config = SegmenterConfig()
    if args.floor_hold is not None:
        config = replace(config, floor_hold=args.floor_hold != "off", floor_hold_after=args.floor_hold == "after")
    peaks = [float(p) for p in args.peaks.split(",") if p]
    rows: list[dict] = [{"peak_dbfs": peak} for peak in peaks] if args.cancel_only else []
    for peak in [] if args.cancel_only else peaks:
        rng = np.random.default_rng(args.seed)
        heard = commanded = 0
        acted: Counter[str] = Counter()
        said: dict[str, list[str]] = {}
        late: list[float] = []  # each utterance's onset after the loudspeaker fell silent, s
        escaped: list[str] = []  # sentences of which an utterance began after the tail: published though the robot's
        for text, voice, end in zip(sentences, voices, ends, strict=True):
            x = through_mic(np.clip(in_room(at_level(voice, peak), args.floor, rng), -1.0, 1.0), args.mic_rate)
            segs = stream(engine, x, config)
            heard += bool(segs)
            late += [start + config.pre_roll_s - end for _, start, _, _, _ in segs]
            escaped += [text for _, start, _, _, _ in segs if start + config.pre_roll_s - end > TAIL_S][:1]
            taken = [policy.takes(cmd, conf) for _, _, _, cmd, conf in segs]
            commanded += any(cmd is not None for *_, cmd, _ in segs)
            for what in filter(None, taken):
                acted[what] += 1
                said.setdefault(what, []).append(text)
        rows.append({"peak_dbfs": peak, "sentences": len(sentences), "heard_as_speech": heard,
                     "heard_as_a_command": commanded, "acted_on": dict(acted), "walks": acted[WALK], "asks": acted[ASK],
                     "sentences_per_command": said, "onset_after_voice_s_max": round(max(late), 3) if late else None,
                     "utterances_after_voice": sum(t > 0 for t in late), "escaped_the_tail": escaped})
        print(json.dumps(rows[-1]), flush=True)
    if args.over is not None:
        stops = [np.frombuffer(it.pcm, "<i2") / 32768.0 for it in heldout_items(args.over, args.workers)
                 if it.label == WORDS.index("stop") and it.condition == "clean" and it.family != "noise"]
        alone = None if args.cancel_only else stop_over_voice(
            engine, config, voices, stops, None, args.person, args.floor, args.mic_rate, np.random.default_rng(args.seed))
        for row in rows:
            row["stops"] = len(stops)
            if not args.cancel_only:
                row["stop_over_voice"] = stop_over_voice(engine, config, voices, stops, row["peak_dbfs"], args.person,
                                                         args.floor, args.mic_rate, np.random.default_rng(args.seed))
                row["stop_alone"] = alone
            if args.cancel:
                over = stop_over_cancelled(engine, config, dry, stops, row["peak_dbfs"], args.person, args.floor,
                                           args.mic_rate, rt60, np.random.default_rng(args.seed), args.warm, ways,
                                           args.after, args.draw_sentences, stops_said, own_stop_from(args.own_stop),
                                           args.seed if args.memory else None)
                row.update(stop_over_echo=dict(over.heard), stop_over_echo_published=dict(over.heard_published),
                           own_stop_onsets=over.own_stop_onsets,
                           own_stop_dropped={w: dict(c) for w, c in over.own_stop_dropped.items()},
                           stops_early=over.early,
                           stops_early_heard=dict(over.early_heard), stray_commands_echo=dict(over.stray),
                           stray_commands_echo_at=over.stray_at, stray_commands_published=dict(over.published),
                           stray_commands_published_at=over.published_at)
            if args.recall:
                over = stop_over_recalled(engine, config, dry, stops, row["peak_dbfs"], args.person, args.floor,
                                          args.mic_rate, rt60, np.random.default_rng(args.seed))
                row.update(stop_over_recalled=dict(over.heard), stops_early_recalled=over.early,
                           stops_early_heard_recalled=dict(over.early_heard))
            print(json.dumps({k: row[k] for k in ("peak_dbfs", "stop_over_voice", "stop_alone", "stops",
                                                  "stop_over_echo", "stop_over_echo_published", "own_stop_dropped",
                                                  "own_stop_onsets",
                                                  "stops_early", "stops_early_heard",
                                                  "stray_commands_echo", "stray_commands_echo_at",
                                                  "stray_commands_published", "stray_commands_published_at",
                                                  "stop_over_recalled", "stops_early_recalled", "stops_early_heard_recalled")
                              if k in row}),
                  flush=True)
    print()
    if not args.cancel_only:
        print(f"{'own voice':>10} {'heard':>9} {'a command':>9} {'walk':>4} {'ask':>4} {'latest onset':>12} "
              f"{'past tail':>9}  acted on")
    for r in [] if args.cancel_only else rows:
        print(f"{r['peak_dbfs']:+6.0f} dBFS {r['heard_as_speech']:4d}/{r['sentences']:<4d} {r['heard_as_a_command']:9d} "
              f"{r['walks']:4d} {r['asks']:4d} {r['onset_after_voice_s_max']:+11.2f}s {len(r['escaped_the_tail']):9d}  "
              f"{r['acted_on']}")
    if args.over is not None and not args.cancel_only:
        print(f"a person's \"stop\" at {args.person:.0f} dBFS over the robot's voice (held-out seed {args.over}): "
              + ", ".join(f"{r['stop_over_voice']}/{r['stops']} over {r['peak_dbfs']:.0f} dBFS" for r in rows)
              + f"; {rows[0]['stop_alone']}/{rows[0]['stops']} alone")
    if args.over is not None and args.cancel:
        print(f"the same \"stop\"s {'just after' if args.after else 'over'} the robot's voice through a room and a "
              f"small loudspeaker (after {args.warm} sentences"
              f"{'; the canceller recalling a memory of three others' if args.memory else ''}; floor hold "
              f"{args.floor_hold or ('on' if config.floor_hold else 'off')}), "
              f"{' / '.join(ways)} (the echo canceller's ways; learnt first, fitted: the default): "
              + ", ".join(
                  f"{' / '.join(str(r['stop_over_echo'][w]) for w in ways)} of {r['stops']} at {r['peak_dbfs']:.0f} "
                  f"dBFS (published: {' / '.join(str(r['stop_over_echo_published'][w]) for w in ways)}, "
                  f"own-stop setting {args.own_stop or OWN_STOP_DEFAULT}; of the {r['stops_early']} begun within "
                  f"{EARLY_S:.1f} s of the sentence's echo: "
                  f"{' / '.join(str(r['stops_early_heard'][w]) for w in ways)}; commands heard elsewhere: "
                  f"{' / '.join(str(r['stray_commands_echo'][w]) for w in ways)}, of which the service would "
                  f"publish {' / '.join(str(r['stray_commands_published'][w]) for w in ways)})" for r in rows))
    if args.over is not None and args.recall:
        print(f"the same \"stop\"s over the robot's first sentence of a run, {' / '.join(RECALLS)} (the echo "
              "canceller's memory of three sentences of an earlier run): " + ", ".join(
                  f"{' / '.join(str(r['stop_over_recalled'][w]) for w in RECALLS)} of {r['stops']} at "
                  f"{r['peak_dbfs']:.0f} dBFS (of the {r['stops_early_recalled']} begun within {EARLY_S:.1f} s of the "
                  f"sentence's echo: {' / '.join(str(r['stops_early_heard_recalled'][w]) for w in RECALLS)})" for r in rows))
    print(f"({len(sentences)} sentences the robot can say, espeak-ng {DEFAULT_VOICE} at {DEFAULT_RATE} words a minute; "
          f"hiss {args.floor:.0f} dBFS RMS; microphone {args.mic_rate or SAMPLE_RATE} Hz; "
          f"{'a room, the loudspeaker 0.1 m away' if args.room else 'no room'}; latest onset: an utterance's, after the "
          f"loudspeaker fell silent; past tail: sentences with one after the {TAIL_S} s tail)")
    if args.json:
        args.json.write_text(json.dumps({"rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
