"""The default engine: a command spotter (pretrained speech embedding + a small trained head).

One utterance (a trimmed WAV file or a VAD-cut stretch of a stream) is centred in a 2 s window,
embedded (the head's speech embedding: `spotter.embedders`) and classified over the vocabulary plus "other" (`spotter.head`). The
most probable class is published if it is a command and its raw probability reaches the command's
`accept` threshold; the published confidence is calibrated so that 0.5 is `accept` and 0.85 is
`sure` (for "go": walk without asking). An utterance longer than `MAX_SPEECH_S` is not one command
word and is rejected without classifying it.

A head made by enrolment keeps the calibrated head's last layer: its "go" is capped just below 0.85
(the robot asks) unless the calibrated head is sure as well.

A walk gate (`WalkGate`, round 14b) does the same with a second head on another speech embedding: a "go" the
head is sure of is capped just below 0.85 unless the gate's head is sure of "go" too, so the robot walks
unasked only where both embeddings agree (their errors differ: on one bench draw the Whisper head walked on
"co" and the speech-embedding head on nothing, on another the speech-embedding head walked on two one-phoneme
neighbours and the gated Whisper head on none). `HRI_VOICE_WALK_GATE`: a head file, or `none`; by default a
head on another embedding than the speech embedding is gated by the shipped speech-embedding head
(`spotter/head-speech-embedding.npz`), and a speech-embedding head (an enrolled one) is not gated.

The head is `HRI_VOICE_HEAD` if set, else the enrolled head in the state folder if there is one,
else the committed `spotter/head.npz`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from schemas.messages import Command
from services.voice.engine import EngineError, Recognition
from services.voice.spotter.embedders import SPEECH_EMBEDDING, UtteranceEmbedder, embedder_for
from services.voice.spotter.features import MAX_SPEECH_S, FeatureError, speech_seconds
from services.voice.spotter.head import DEFAULT_HEAD, SPEECH_EMBEDDING_HEAD, SURE_CONFIDENCE, Head, HeadError

NO_GATE = "none"


@dataclass
class WalkGate:
    """A second head, on another speech embedding, that must be sure of "go" too before the robot walks unasked."""

    head: Head
    embedder: UtteranceEmbedder

    def confidence(self, pcm: bytes) -> float:
        """The gate head's published confidence that this utterance is "go" (0 if it hears something else)."""
        probs = self.head.probabilities(self.embedder.utterance(pcm))[0]
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

    def __init__(self, head: Head, embedder: UtteranceEmbedder | None = None, gate: WalkGate | None = None) -> None:
        unknown = [w for w in head.vocabulary if w not in {c.value for c in Command}]
        if unknown:
            raise EngineError(f"spotter head vocabulary has words that are not commands: {unknown}")
        self.head = head
        self.embedder = embedder or embedder_for(head.embedding)
        self.gate = gate

    @classmethod
    def from_path(cls, path: Path | str | None = None, walk_gate: str | None = None) -> SpotterEngine:
        try:
            head = Head.load(path or DEFAULT_HEAD)
            return cls(head, gate=walk_gate_for(head, walk_gate))
        except (HeadError, FeatureError) as exc:
            raise EngineError(str(exc)) from None

    def recognise(self, pcm: bytes) -> Recognition:
        t0 = time.perf_counter()
        audio_s = speech_seconds(pcm)
        if audio_s > MAX_SPEECH_S:
            return Recognition(None, "(long utterance)", 0.0, self.name, time.perf_counter() - t0, audio_s,
                               {"reason": f"longer than {MAX_SPEECH_S} s: not one command word"})
        feats = self.embedder.utterance(pcm)
        probs = self.head.probabilities(feats)[0]
        best = int(probs.argmax())
        n = len(self.head.vocabulary)
        top_cmd = int(probs[:n].argmax())
        conf = self.head.confidence(top_cmd, float(probs[top_cmd]))
        detail = {"p": {c: round(float(p), 3) for c, p in zip(self.head.classes, probs, strict=True) if p >= 0.01}}
        word = self.head.classes[best]
        if best == n:
            command, reason = None, "other"
            conf = min(conf, 0.49)
        elif conf < 0.5:
            command, reason = None, f"{word} below threshold {self.head.accept[best]:.3f}"
        else:
            command, reason = Command(word), "accepted"
            if command == Command.GO and conf >= SURE_CONFIDENCE and self.head.base_last is not None:
                base_conf = self.head.confidence(best, float(self.head.probabilities(feats, base=True)[0][best]))
                if base_conf < SURE_CONFIDENCE:  # enrolment alone never makes the robot walk unasked
                    conf, reason = SURE_CONFIDENCE - 0.01, "accepted (enrolled; the calibrated head is not sure: ask)"
            if command == Command.GO and conf >= SURE_CONFIDENCE and self.gate is not None:
                gate_conf = self.gate.confidence(pcm)
                detail["gate"] = round(gate_conf, 3)
                if gate_conf < SURE_CONFIDENCE:  # one embedding alone never makes the robot walk unasked
                    conf, reason = SURE_CONFIDENCE - 0.01, "accepted (the walk gate's head is not sure: ask)"
        detail["reason"] = reason
        return Recognition(command, word, conf, self.name, time.perf_counter() - t0, audio_s, detail)
