"""The default engine: a command spotter (pretrained speech embedding + a small trained head).

One utterance (a trimmed WAV file or a VAD-cut stretch of a stream) is centred in a 2 s window,
embedded (the head's speech embedding: `spotter.embedders`) and classified over the vocabulary plus "other" (`spotter.head`). The
most probable class is published if it is a command and its raw probability reaches the command's
`accept` threshold; the published confidence is calibrated so that 0.5 is `accept` and 0.85 is
`sure` (for "go": walk without asking). An utterance longer than `MAX_SPEECH_S` is not one command
word and is not classified whole: only a "stop" within it is looked for (`LONG_STOP`, below).

A head made by enrolment keeps the calibrated head's last layer: its "go" is capped just below 0.85
(the robot asks) unless the calibrated head is sure as well.

A walk gate (`WalkGate`, round 14b) does the same with a second head on another speech embedding: a "go" the
head is sure of is capped just below 0.85 unless the gate's head is sure of "go" too, so the robot walks
unasked only where both embeddings agree (their errors differ: on one bench draw the Whisper head walked on
"co" and the speech-embedding head on nothing, on another the speech-embedding head walked on two one-phoneme
neighbours and the gated Whisper head on none). `HRI_VOICE_WALK_GATE`: a head file, or `none`; by default a
head on another embedding than the speech embedding is gated by the shipped speech-embedding head
(`spotter/head-speech-embedding.npz`), and a speech-embedding head (an enrolled one) is not gated.

The agreement veto (`agree_min`, `HRI_VOICE_AGREE_MIN`, round voice27) asks the gate's head about every command
the head would publish: unless the gate's head gives that same command at least `agree_min` probability, the
utterance is not understood. It only ever removes a publication (no walk, no question the head alone would not
make), costs one more embedding (~10 ms) per command the head accepts, and needs a gate (an enrolled head has none:
the veto is off there).

The decoder's rescue (`decoder`, `HRI_VOICE_DECODER=on`, round voice30; `spotter/decoder.py`): where the head
accepts no command, Whisper's own decoder reads the encoder output the head's embedding was pooled from, and the
utterance is heard as the command it writes first if it is sure enough of it (`decoder.RESCUE_AT`,
`decoder.ENDS_AT`), with a confidence from 0.5 to 0.6: a rescued "go" is asked about, never walked on, and a
rescued "yes" confirms no question. Only for a head on Whisper's encoder (the default); one short decoding
(~20-25 ms) for each utterance the head does not accept, none for one it does.

"stop" within a phrase (`stop_in_phrase`, `HRI_VOICE_STOP_IN_PHRASE`, on by default since round voice31; `PhraseStop`;
with `down_in_phrase`, `HRI_VOICE_DOWN_IN_PHRASE`, off, "down" too at 0.85: round voice35, `DOWN_IN_PHRASE`):
where the head accepts no command, windows of `PhraseStop.window_s` across the utterance are classified as well, and
the utterance is heard as "stop" if one of them is surely enough "stop" ("please stop", "stop it"). Only "stop":
stopping is the safe direction, while a "go" at a phrase's end may be "don't go". Costs an embedding per window
(~10 ms) for each utterance the head does not accept, none for one it does.

"stop" within a sentence (`stop_in_long`, `HRI_VOICE_STOP_IN_LONG`, on by default since round voice33;
`LONG_STOP`): an utterance longer than `MAX_SPEECH_S` is not one command word and is not classified whole; with
this on, its windows (as above, up to `LONG_STOP_MAX_S` of audio) are looked at for a "stop" at the stricter
`LONG_STOP.at` ("robot, please stop walking now"). Costs an embedding per window of such an utterance (up to 27 for 6 s; decoding a
2.7 s sentence takes about 110 ms).

The warped second look (`warped_look`, `HRI_VOICE_WARPED_LOOK`, round voice34; `WarpedLook`): where the head accepts
no command but came near (its most probable command at half that command's accept or more), the utterance is heard
again at two other speeds (resampled: faster and higher, slower and lower, as another speaker's vocal tract), and the
three hearings' class probabilities are combined (geometric mean); a command the combination accepts is published
with a confidence of at most `WarpedLook.cap` (0.6): enough to act on, too little for a "go" to walk unasked or a
"yes" to confirm a question. Two more embeddings (~20 ms) for each utterance that comes near, none for the others.

The head is `HRI_VOICE_HEAD` if set, else the enrolled head in the state folder if there is one,
else the committed `spotter/head.npz`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import resample_poly

from schemas.messages import Command
from services.runtime.flags import parse_flag
from services.voice.audio import SAMPLE_RATE
from services.voice.engine import EngineError, Recognition
from services.voice.spotter.decoder import FirstWord
from services.voice.spotter.embedders import SPEECH_EMBEDDING, UtteranceEmbedder, embedder_for
from services.voice.spotter.features import MAX_SPEECH_S, FeatureError, speech_seconds
from services.voice.spotter.head import DEFAULT_HEAD, SPEECH_EMBEDDING_HEAD, SURE_CONFIDENCE, Head, HeadError
from services.voice.spotter.whisper import WhisperEmbedder

NO_GATE = "none"
AGREE_ENV = "HRI_VOICE_AGREE_MIN"
DEFAULT_AGREE_MIN = 0.0
"""Off: round voice27 (0.25) heard 0.750 -> 0.663 of held-out commands for 8.7 -> 5.2 % of other words (voice README)."""
DECODER_ENV = "HRI_VOICE_DECODER"
DEFAULT_DECODER = False
"""Off: rounds voice30 and 30b heard 10-15 more of 504 held-out commands but took 8-31 more of 1,914 other words and
asked 6-33 more questions; 30b failed its confirmation seed (voice README, round 30)."""
STOP_IN_PHRASE_ENV = "HRI_VOICE_STOP_IN_PHRASE"
DEFAULT_STOP_IN_PHRASE = True
"""On since round voice31 (rule docs/experiments/rules/voice31_rule.txt): on fresh held-out seeds "stop" said within a
phrase was heard in 57 instead of 31 of 96 clips, with 4 more of 1,914 other words taken (all for "stop"), no walk and
no question added (voice README)."""
STOP_IN_LONG_ENV = "HRI_VOICE_STOP_IN_LONG"
DEFAULT_STOP_IN_LONG = True
"""On since round voice33 (rule docs/experiments/rules/voice33_rule.txt): on a fresh held-out seed "stop" said in a
sentence longer than 1.7 s was heard in 23 instead of 0 of 47 clips, and in none of 64 sentences without it; a real
person reading and a dialogue gained no command; 2 more of 504 held-out commands heard (voice README)."""
WARPED_LOOK_ENV = "HRI_VOICE_WARPED_LOOK"
DEFAULT_WARPED_LOOK = False
"""Off: round voice34 (rule docs/experiments/rules/voice34_rule.txt) heard 11 more of 504 held-out commands for 27 more
of 1,914 other words and 36 more questions on "don't ... go" streams (voice README)."""
LONG_STOP_MAX_S = 6.0
"""The longest utterance whose windows are looked at: the stream segmenter's `max_utterance_s`. A longer file is
rejected as before (hundreds of windows)."""


def agree_min_from(raw: str | float | None) -> float:
    """The agreement veto's probability from `HRI_VOICE_AGREE_MIN` / `--agree-min` (None: the default); EngineError
    unless a number from 0 (off) up to, not including, 1."""
    if raw is None or raw == "":
        return DEFAULT_AGREE_MIN
    try:
        value = float(raw)
    except ValueError:
        value = -1.0
    if not 0.0 <= value < 1.0:
        raise EngineError(f"{AGREE_ENV}={raw!r}: a probability from 0 (off) up to, not including, 1")
    return value


def _on_off(raw: str | bool | None, default: bool, env: str) -> bool:
    """An on/off setting from its variable `env` or option (None or "": `default`); EngineError unless on or off
    (1/0, true/false, yes/no)."""
    if raw is None or raw == "":
        return default
    value = raw if isinstance(raw, bool) else parse_flag(raw)
    if value is None:
        raise EngineError(f"{env}={raw!r}: on or off")
    return value


def decoder_from(raw: str | bool | None) -> bool:
    """Whether the decoder's rescue is on, from `HRI_VOICE_DECODER` / `--decoder`."""
    return _on_off(raw, DEFAULT_DECODER, DECODER_ENV)


def stop_in_phrase_from(raw: str | bool | None) -> bool:
    """Whether "stop" is also looked for within a phrase, from `HRI_VOICE_STOP_IN_PHRASE` / `--stop-in-phrase`."""
    return _on_off(raw, DEFAULT_STOP_IN_PHRASE, STOP_IN_PHRASE_ENV)


def stop_in_long_from(raw: str | bool | None) -> bool:
    """Whether "stop" is also looked for within an utterance longer than `MAX_SPEECH_S`, from `HRI_VOICE_STOP_IN_LONG`
    / `--stop-in-long`."""
    return _on_off(raw, DEFAULT_STOP_IN_LONG, STOP_IN_LONG_ENV)


def warped_look_from(raw: str | bool | None) -> bool:
    """Whether the warped second look is on, from `HRI_VOICE_WARPED_LOOK` / `--warped-look`."""
    return _on_off(raw, DEFAULT_WARPED_LOOK, WARPED_LOOK_ENV)


@dataclass(frozen=True)
class WarpedLook:
    """A second hearing, at other speeds, of an utterance the head came near to accepting (round voice34). Chosen on
    the tune voices only (voice README): on 690 tune commands and 605 tune other words (one-edit neighbours among
    them) the head alone heard 0.874 and took 47 words; with this look 0.890 (11 more: "stand", "no", "down", ...) and
    48 ("sand" for "stand"). Speeds 0.9 / 1.1 or the copies' plain mean did no better; one copy alone at 0.95 heard
    17 more commands for 11 more words."""

    speeds: tuple[tuple[int, int], ...] = ((20, 19), (20, 21))
    """Each copy's resampling (up, down): 20/19 plays the utterance at 0.95 of its speed, 20/21 at 1.05."""
    near: float = 0.5
    """Looked at again where the head's most probable command has at least this share of its accept probability."""
    cap: float = 0.6
    """The highest confidence a command heard so is published with."""

    def copies(self, pcm: bytes) -> list[bytes]:
        """The utterance at the other speeds (16-bit PCM)."""
        x = np.frombuffer(pcm, "<i2").astype(np.float64)
        return [np.clip(np.round(resample_poly(x, up, down)), -32768, 32767).astype("<i2").tobytes()
                for up, down in self.speeds]


@dataclass(frozen=True)
class PhraseStop:
    """ "stop" looked for in windows across an utterance the head heard no command in (round voice31). Chosen on the
    tune voices' phrases and one-edit neighbours only (voice README): 0.7 s windows at 0.7 heard 20 more of 48 "stop"s
    said within a phrase and 0 more of 498 other words; at 0.5 (the head's own accept) the windows heard "stop" in
    "don't go", "star" and "top"; at 0.85 (sure) about half the gain."""

    window_s: float = 0.7
    """Each window's length: about one word with its edges."""
    hop_s: float = 0.2
    """From one window's start to the next's."""
    at: float = 0.7
    """The published confidence (calibrated: 0.5 is the head's accept, 0.85 its sure) a window's "stop" needs."""
    others: tuple[tuple[str, float], ...] = ()
    """Other commands heard within the utterance this way, each with the confidence a window needs (round voice35:
    "down", as in "sit down"); "stop" wins over them wherever a window hears it."""

    def windows(self, pcm: bytes) -> list[tuple[float, bytes]]:
        """The utterance's windows from its start to its end, each with its start (s); none for an utterance no
        longer than one window."""
        size, hop = round(self.window_s * SAMPLE_RATE) * 2, round(self.hop_s * SAMPLE_RATE) * 2
        if len(pcm) <= size:
            return []
        starts = list(range(0, len(pcm) - size + 1, hop))
        if starts[-1] != len(pcm) - size:
            starts.append(len(pcm) - size)  # the last window ends with the utterance: "please stop"
        return [(k / 2 / SAMPLE_RATE, pcm[k : k + size]) for k in starts]


DOWN_IN_PHRASE = (("down", 0.85),)
"""`PhraseStop.others` with `down_in_phrase` on (round voice35). Chosen on the tune voices only (voice README): windows
at 0.85 heard "down" in 11 of 30 tune phrases ("sit down", "get down", "lie down", ...) and in 2 of 168 without it
("download", "a good town"); at 0.7 in 15 of 30, and in 6 of 168."""
DOWN_IN_PHRASE_ENV = "HRI_VOICE_DOWN_IN_PHRASE"
DEFAULT_DOWN_IN_PHRASE = False
"""Off: round voice35 (rule docs/experiments/rules/voice35_rule.txt) heard "down" in a phrase 5 more times in 24 and 3
more lone held-out "down"s, for 6 more of 1,914 held-out other words; the extra rows' words rose 1.03 points, over its
1.0 (voice README)."""


def down_in_phrase_from(raw: str | bool | None) -> bool:
    """Whether "down" is also heard within a phrase, from `HRI_VOICE_DOWN_IN_PHRASE` / `--down-in-phrase`."""
    return _on_off(raw, DEFAULT_DOWN_IN_PHRASE, DOWN_IN_PHRASE_ENV)


LONG_STOP = PhraseStop(at=0.8)
"""The windows across an utterance longer than `MAX_SPEECH_S` (round voice33). A sentence has more windows than a
phrase, so more chances of a false "stop": chosen on the tune voices only (voice README), 0.8 heard "stop" in 35 of 64
tune sentences holding one and in none of 79 without (0.7: 41 of 64 and 2 of 79; 0.85: 21 of 64)."""


@dataclass
class WalkGate:
    """A second head, on another speech embedding, that must be sure of "go" too before the robot walks unasked."""

    head: Head
    embedder: UtteranceEmbedder

    def probabilities(self, pcm: bytes) -> np.ndarray:
        """The gate head's probabilities of its classes for this utterance."""
        return self.head.probabilities(self.embedder.utterance(pcm))[0]

    def probability(self, probs: np.ndarray, word: str) -> float:
        """The gate head's probability of `word` (0 for a word outside its vocabulary)."""
        return float(probs[self.head.vocabulary.index(word)]) if word in self.head.vocabulary else 0.0

    def confidence(self, probs: np.ndarray) -> float:
        """The gate head's published confidence that the utterance of `probs` is "go" (0 if it hears something
        else)."""
        go = self.head.vocabulary.index(Command.GO.value)
        if int(probs.argmax()) != go:
            return 0.0
        return self.head.confidence(go, float(probs[go]))


def walk_gate_for(head: Head, spec: str | None = None) -> WalkGate | None:
    """The gate for `head`: `spec` a head file, `none`, or None for the default (the shipped speech-embedding
    head for a head on another embedding; no gate for a speech-embedding head). HeadError / FeatureError if the
    gate's head cannot be used, or reads the same embedding as `head` (no second opinion)."""
    if spec == NO_GATE or (spec is None and head.embedding == SPEECH_EMBEDDING):
        return None
    gate = Head.load(spec or SPEECH_EMBEDDING_HEAD)
    if Command.GO.value not in gate.vocabulary:
        raise HeadError(f"walk gate {spec or SPEECH_EMBEDDING_HEAD}: its vocabulary has no 'go'")
    if gate.embedding == head.embedding:
        raise HeadError(f"walk gate {spec or SPEECH_EMBEDDING_HEAD} reads {gate.embedding}, as the head does: "
                        f"a gate must read another embedding (or set HRI_VOICE_WALK_GATE={NO_GATE})")
    return WalkGate(gate, embedder_for(gate.embedding))


class SpotterEngine:
    name = "spotter"

    def __init__(self, head: Head, embedder: UtteranceEmbedder | None = None, gate: WalkGate | None = None,
                 agree_min: float = DEFAULT_AGREE_MIN, decoder: bool = DEFAULT_DECODER,
                 stop_in_phrase: bool = DEFAULT_STOP_IN_PHRASE, stop_in_long: bool = DEFAULT_STOP_IN_LONG,
                 warped_look: bool = DEFAULT_WARPED_LOOK, down_in_phrase: bool = DEFAULT_DOWN_IN_PHRASE) -> None:
        unknown = [w for w in head.vocabulary if w not in {c.value for c in Command}]
        if unknown:
            raise EngineError(f"spotter head vocabulary has words that are not commands: {unknown}")
        self.head = head
        self.embedder = embedder or embedder_for(head.embedding)
        self.gate = gate
        self.agree_min = agree_min if gate is not None else 0.0
        """The agreement veto's probability; 0 (off) without a gate."""
        self.decoder: FirstWord | None = None
        """The decoder's rescue; None (off) unless asked for and the head reads Whisper's encoder."""
        if decoder and isinstance(self.embedder, WhisperEmbedder):
            self.decoder = FirstWord(self.embedder.ctranslate2_model, str(self.embedder.path / "tokenizer.json"),
                                     head.vocabulary)
        others = DOWN_IN_PHRASE if down_in_phrase and Command.DOWN.value in head.vocabulary else ()
        self.phrase_stop: PhraseStop | None = (
            PhraseStop(others=others) if stop_in_phrase and Command.STOP.value in head.vocabulary else None)
        """"stop" (and with `down_in_phrase` "down") within a phrase; None (off) unless asked for and the head has
        "stop"."""
        self.long_stop: PhraseStop | None = (
            LONG_STOP if stop_in_long and Command.STOP.value in head.vocabulary else None)
        """"stop" within an utterance longer than `MAX_SPEECH_S`; None (off) unless asked for and the head has
        "stop"."""
        self.warped_look: WarpedLook | None = WarpedLook() if warped_look else None
        """The warped second look; None (off) unless asked for."""

    @classmethod
    def from_path(cls, path: Path | str | None = None, walk_gate: str | None = None,
                  agree_min: str | float | None = None, decoder: str | bool | None = None,
                  stop_in_phrase: str | bool | None = None, stop_in_long: str | bool | None = None,
                  warped_look: str | bool | None = None, down_in_phrase: str | bool | None = None) -> SpotterEngine:
        try:
            head = Head.load(path or DEFAULT_HEAD)
            return cls(head, gate=walk_gate_for(head, walk_gate), agree_min=agree_min_from(agree_min),
                       decoder=decoder_from(decoder), stop_in_phrase=stop_in_phrase_from(stop_in_phrase),
                       stop_in_long=stop_in_long_from(stop_in_long), warped_look=warped_look_from(warped_look),
                       down_in_phrase=down_in_phrase_from(down_in_phrase))
        except (HeadError, FeatureError, ValueError) as exc:
            raise EngineError(str(exc)) from None

    def recognise(self, pcm: bytes) -> Recognition:
        t0 = time.perf_counter()
        audio_s = speech_seconds(pcm)
        if audio_s > MAX_SPEECH_S:
            heard = (self._heard_within(pcm, self.long_stop)
                     if self.long_stop is not None and audio_s <= LONG_STOP_MAX_S else None)
            if heard is not None:
                _, at_s, conf = heard
                return Recognition(Command.STOP, Command.STOP.value, conf, self.name, time.perf_counter() - t0,
                                   audio_s, {"reason": f"stop within a long utterance at {at_s:.1f} s"})
            return Recognition(None, "(long utterance)", 0.0, self.name, time.perf_counter() - t0, audio_s,
                               {"reason": f"longer than {MAX_SPEECH_S} s: not one command word"})
        encoded: np.ndarray | None = None
        if self.decoder is not None:  # the encoder output is kept for the decoder
            assert isinstance(self.embedder, WhisperEmbedder)
            encoded = self.embedder.encoded(pcm)
            feats = self.embedder.pool(encoded)
        else:
            feats = self.embedder.utterance(pcm)
        probs = self.head.probabilities(feats)[0]
        best = int(probs.argmax())
        n = len(self.head.vocabulary)
        top_cmd = int(probs[:n].argmax())
        conf = self.head.confidence(top_cmd, float(probs[top_cmd]))
        detail = {"p": {c: round(float(p), 3) for c, p in zip(self.head.classes, probs, strict=True) if p >= 0.01}}
        word = self.head.classes[best]
        head_refused = best == n or conf < 0.5  # the head accepts no command (what the decoder may rescue)
        if best == n:
            command, reason = None, "other"
            conf = min(conf, 0.49)
        elif conf < 0.5:
            command, reason = None, f"{word} below threshold {self.head.accept[best]:.3f}"
        else:
            command, reason = Command(word), "accepted"
            gate_probs = None
            if self.gate is not None and self.agree_min > 0:
                gate_probs = self.gate.probabilities(pcm)
                agree = self.gate.probability(gate_probs, word)
                detail["agree"] = round(agree, 3)
                if agree < self.agree_min:  # the other embedding does not hear this command: not understood
                    command, conf = None, min(conf, 0.49)
                    reason = f"{word}: the walk gate's head gives it {agree:.3f}, below {self.agree_min}"
            if command == Command.GO and conf >= SURE_CONFIDENCE and self.head.base_last is not None:
                base_conf = self.head.confidence(best, float(self.head.probabilities(feats, base=True)[0][best]))
                if base_conf < SURE_CONFIDENCE:  # enrolment alone never makes the robot walk unasked
                    conf, reason = SURE_CONFIDENCE - 0.01, "accepted (enrolled; the calibrated head is not sure: ask)"
            if command == Command.GO and conf >= SURE_CONFIDENCE and self.gate is not None:
                gate_conf = self.gate.confidence(gate_probs if gate_probs is not None else self.gate.probabilities(pcm))
                detail["gate"] = round(gate_conf, 3)
                if gate_conf < SURE_CONFIDENCE:  # one embedding alone never makes the robot walk unasked
                    conf, reason = SURE_CONFIDENCE - 0.01, "accepted (the walk gate's head is not sure: ask)"
        look = self.warped_look
        if head_refused and look is not None and probs[top_cmd] >= look.near * self.head.accept[top_cmd]:
            heard = self._warped(look, pcm, feats)
            detail["warped"] = {c: round(float(p), 3) for c, p in zip(self.head.classes, heard, strict=True)
                                if p >= 0.01}
            again = int(heard.argmax())
            if again < n and heard[again] >= self.head.accept[again]:  # heard at other speeds as well: a command
                word, command = self.head.classes[again], Command(self.head.classes[again])
                conf = min(self.head.confidence(again, float(heard[again])), look.cap)
                reason = f"heard at other speeds (at most {look.cap}: a go asks, a yes confirms nothing)"
        if head_refused and command is None and encoded is not None:
            assert self.decoder is not None
            opinion = self.decoder.of(encoded)
            detail["decoder"] = {"first": {w: round(p, 3) for w, p in opinion.first.items() if p >= 0.01},
                                 "best": opinion.best, "ends": round(opinion.ends, 3)}
            rescued = opinion.rescue()
            if rescued is not None:  # the head heard no command; the decoder writes one first, sure of it
                word, conf = rescued
                command, reason = Command(word), "rescued by the decoder (below 0.85 and 0.7: asks, confirms nothing)"
        if head_refused and command is None and self.phrase_stop is not None:  # not after the veto: that head did hear
            heard = self._heard_within(pcm, self.phrase_stop)
            if heard is not None:
                word, at_s, conf = heard
                command, reason = Command(word), f"{word} within the utterance at {at_s:.1f} s"
        detail["reason"] = reason
        return Recognition(command, word, conf, self.name, time.perf_counter() - t0, audio_s, detail)

    def _warped(self, look: WarpedLook, pcm: bytes, feats: np.ndarray) -> np.ndarray:
        """The head's class probabilities over the utterance (`feats`) and its copies at `look`'s speeds: their
        geometric mean, normalised."""
        hearings = [feats] + [self.embedder.utterance(copy) for copy in look.copies(pcm)]
        logs = np.log(np.clip(np.concatenate([self.head.probabilities(f) for f in hearings]), 1e-6, 1.0))
        mean = np.exp(logs.mean(axis=0))
        return mean / mean.sum()

    def _heard_within(self, pcm: bytes, finder: PhraseStop) -> tuple[str, float, float] | None:
        """Where a window of the utterance (`finder.windows`) is surely enough "stop" (`finder.at`), or one of
        `finder.others`: the word, the window's start (s) and the best such window's confidence; "stop" wherever a
        window hears it, else the surest other; None if no window is."""
        needs = {Command.STOP.value: finder.at, **dict(finder.others)}
        best: dict[str, tuple[float, float]] = {}
        for start_s, window in finder.windows(pcm):
            probs = self.head.probabilities(self.embedder.utterance(window))[0]
            top = int(probs.argmax())
            word = self.head.classes[top]
            if word not in needs:
                continue
            conf = self.head.confidence(top, float(probs[top]))
            if conf >= needs[word] and (word not in best or conf > best[word][1]):
                best[word] = (start_s, conf)
        if not best:
            return None
        word = Command.STOP.value if Command.STOP.value in best else max(best, key=lambda w: best[w][1])
        return (word, *best[word])
