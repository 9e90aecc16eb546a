"""Commands said inside short phrases, and "go" after a word that forbids it (prints figures; not a test).

The robot obeys single command words. People do not always say one word: "please stop", "let's go", "don't go".
This bench asks what the robot does with such speech, on held-out voices only (`corpus.voices("heldout")` and the
voices of `corpus.HELDOUT_EXTRA` that can speak here), in two ways:

- **One utterance** (a WAV file, or a stream in which the words run together): each phrase of `GROUPS` and each
  sentence of `SENTENCES` is said
  `--renderings` times by random held-out voices at random speeds, half clean and half with the training's kind of
  augmentation (noise at 3-30 dB, reverberation, band limits, tempo; other seeds), trimmed as the service trims a
  WAV file, then recognised.
- **Sentences in a stream**: each rendering of `SENTENCES` in a quiet room, fed through the same stream path, which
  may cut a sentence at its pauses into utterances short enough for the head.
- **Two utterances** (a live stream in which the person pauses between the words): each pair of `PAIRS` is said
  word by word by one voice, joined by each pause of `PAUSES`, in a quiet room and in pink noise 20 dB under the
  voice, and fed in chunks through the service's stream path (`sources.stream_utterances`: Silero VAD, its end
  windows) and the engine.

Each utterance is counted as the reasoner's policy takes it alone (`voice_bench.Policy`, read from the knowledge
file): a "go" walks at once at or above `^confirm-below` and asks "Shall I walk forward?" between `^min-confidence`
and it. Each stream is also given, utterance by utterance, to the reasoner's own Soar agent (`SoarAgent`, the
knowledge and rules the service loads), each `VoiceCommand` stamped where its utterance ends in the stream: what the
robot does then depends on what came before, e.g. a "go" right after speech that matched no command is asked about
(`agent/56_after_unclear.soar`). `MEANT_PAIRS` ("okay ... go") are the pairs in which the "go" was meant: what that
rule costs.

`--voices train` says the phrases and pairs with the voices the head was trained on instead: their "go" is heard
surely, as an enrolled user's is, which held-out voices' rarely is.

    .venv/bin/python bench/voice_phrases.py --seed 1 [--renderings 8] [--engine spotter] [--voices heldout]
                                            [--knowledge F] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import random
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import ASK, WALK, Policy, add_spotter_options, loud_frames, spotter_settings  # noqa: E402
from services.reasoner.agent_host import (  # noqa: E402
    KNOWLEDGE_FILE,
    AgentConfig,
    CommandInput,
    DecisionOutput,
    Memory,
    MotionOutput,
    SoarAgent,
)
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH, from_pcm, to_pcm  # noqa: E402
from services.voice.engine import Engine, Recognition, make_engine  # noqa: E402
from services.voice.sources import CHUNK_S, stream_utterances  # noqa: E402
from services.voice.spotter.features import MAX_SPEECH_S, speech_seconds  # noqa: E402
from services.voice.training import augment, corpus, dataset, tts  # noqa: E402

GROUPS: dict[str, tuple[str, tuple[str, ...]]] = {
    "go forbidden": ("must not walk", (
        "don't go", "do not go", "never go", "no go", "don't go yet", "you can't go", "don't go there",
        "no, don't go", "wait, don't go", "please don't go")),
    "go-words": ("must not walk", (
        "go away", "go home", "go back", "gone", "going", "goes", "to go", "ago", "cargo", "go slow")),
    "go in a phrase": ("a walk or a question is what was meant", (
        "let's go", "go now", "go forward", "okay go", "go ahead", "ready, go", "now go", "go go")),
    "stop in a phrase": ("stopping is what was meant", (
        "please stop", "stop it", "stop now", "stop stop", "stop there", "stop please", "okay stop", "just stop")),
    "stop forbidden": ("a stop is the safe mistake", ("don't stop", "never stop", "don't stop now", "no, don't stop")),
    "other commands in a phrase": ("any command but go", (
        "yes please", "no thanks", "stand up", "sit down", "get down", "why not", "yes sir", "oh no", "oh yes",
        "no no", "down there", "why me")),
}
"""Each group: what the robot should do with it, and its phrases."""
SENTENCES: dict[str, tuple[str, tuple[str, ...]]] = {
    "stop in a sentence": ("stopping is what was meant", (
        "please stop walking right now", "hey robot, stop, there is a chair in the way",
        "I said stop, that is far enough", "can you stop for a second please", "stop moving, someone is coming",
        "okay robot, you can stop there now")),
    "sentences without stop": ("nothing", (
        "the shop on the corner closes at six", "we took the train to the top of the hill",
        "she put the stamps in the drawer", "my brother told me a story about a storm",
        "the bus was full this morning", "put the top back on the bottle", "start the car and wait for me outside",
        "the store is next to the station")),
}
"""Whole sentences, most of them longer than one command word may be (`MAX_SPEECH_S`): what round voice33 is about.
Rendered after everything else, from their own random stream, so that a seed's other clips are those it had before."""

PAIRS: tuple[tuple[str, str], ...] = (
    ("don't", "go"), ("do not", "go"), ("never", "go"), ("no", "go"), ("not", "go"), ("wait", "go"))
"""Said word by word, with a pause between: the first part forbids the "go" that follows."""
MEANT_PAIRS: tuple[tuple[str, str], ...] = (("okay", "go"), ("robot", "go"), ("ready", "go"), ("all right", "go"))
"""Said the same way, but the "go" is meant: a walk, or a question, is right."""
PAUSES = (0.0, 0.12, 0.2, 0.3, 0.5)
"""Seconds of pause between the two parts. Silero ends an utterance after 0.09 s of quiet in a clear stream and
0.15 s otherwise (`SegmenterConfig`), so from about 0.12 s on the "go" is heard on its own."""
ROOMS = (("quiet", None), ("noise 20 dB", 20.0))


def heard(rec: Recognition, policy: Policy) -> str:
    """What the reasoner makes of one recognition alone (`Policy.takes`): a command's name, `WALK` or `ASK` for a
    "go", or "none"."""
    return policy.takes(rec.command, rec.confidence) or "none"


@dataclass(frozen=True)
class Clip:
    group: str
    phrase: str
    voice: str
    condition: str
    pcm: bytes


def _render_phrase(job: tuple[str, dataset.Recipe]) -> Clip | None:
    group, r = job
    try:
        pcm = dataset.render_utterance(r)
    except tts.TtsError:
        return None
    return Clip(group, r.text, r.voice, "noisy" if r.strength else "clean", pcm)


def _tight(x: np.ndarray, floor_db: float = 40.0) -> np.ndarray:
    """`x` cut to its first and last 10 ms within `floor_db` of its loudest 10 ms (a word with no silence around)."""
    loud = loud_frames(x, floor_db, eps=1e-12)
    return x[loud[0] * 160 : (loud[-1] + 1) * 160]


def _render_pair(job: tuple[tuple[str, str], str, float]) -> tuple[np.ndarray, np.ndarray] | None:
    """The pair's two parts, each said alone by the voice at the speed and cut to its sound."""
    (first, second), voice, speed = job
    try:
        return _tight(tts.synthesise(first, voice, speed)), _tight(tts.synthesise(second, voice, speed))
    except tts.TtsError:
        return None


def stream(pcm: bytes, engine: Engine) -> list[tuple[Recognition, float]]:
    """What the robot hears in a stream, utterance by utterance, and where each ends (seconds into the stream): the
    service's VAD cut (`stream_utterances`, its default settings) and the engine, as `services.voice.service` does."""
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    chunks = (pcm[k : k + step] for k in range(0, len(pcm), step))
    return [(u.recognition or engine.recognise(u.pcm), (u.start_s or 0.0) + u.seconds)
            for u in stream_utterances(chunks, "pair", recognise=engine.recognise)]


STREAM_T0 = 1_000_000.0
"""The UNIX time a stream starts at, for its utterances' stamps (only their differences matter)."""
WALKED, ASKED, NEITHER = "walked", "asked", "neither"


def reasoned(agent: SoarAgent, utterances: list[tuple[Recognition, float]]) -> str:
    """What the reasoner's agent, fresh and standing, does with a stream's utterances, each given as the reasoner
    service takes its `VoiceCommand`: `WALKED`, `ASKED` (and did not walk) or `NEITHER`."""
    agent.reset(Memory())
    agent.step(posture="standing")
    outs = []
    for rec, end_s in utterances:
        outs += agent.step(CommandInput.of(rec.message(stamp=STREAM_T0 + end_s)))
    if any(isinstance(o, MotionOutput) and o.action == "walk_forward" for o in outs):
        return WALKED
    return ASKED if any(isinstance(o, DecisionOutput) and o.verdict == "ask" for o in outs) else NEITHER


def in_room(speech: np.ndarray, snr_db: float | None, rng: np.random.Generator) -> bytes:
    """`speech` with 0.8 s of room before and 1 s after, in quiet or in pink noise `snr_db` under it."""
    room = augment.Augment(noise=None if snr_db is None else "pink", snr_db=snr_db or 30.0, peak=0.3, pad_s=(0.8, 1.0))
    return to_pcm(augment.apply(speech, room, rng))


def spoken_pair(first: np.ndarray, second: np.ndarray, pause_s: float, snr_db: float | None,
                rng: np.random.Generator) -> bytes:
    """The two parts with `pause_s` between, in a room (`in_room`)."""
    return in_room(np.concatenate([first, np.zeros(int(pause_s * SAMPLE_RATE)), second]), snr_db, rng)


def _pair_row(results: list[list[tuple[Recognition, float]]], agent: SoarAgent, policy: Policy) -> dict[str, object]:
    """One pause in one room: each utterance as the policy takes it alone, and each stream through the agent."""
    labels = [[heard(rec, policy) for rec, _ in r] for r in results]
    outcomes = Counter(reasoned(agent, r) for r in results)
    return {"streams": len(results), "heard_as_two": sum(len(r) >= 2 for r in results),
            "walked": sum(WALK in r for r in labels), "asked": sum(ASK in r and WALK not in r for r in labels),
            "reasoner": {k: outcomes[k] for k in (WALKED, ASKED, NEITHER)},
            "heard": dict(Counter(" / ".join(r) or "(nothing)" for r in labels).most_common(6))}


SPOTTER_SETTINGS = ("stop_in_phrase", "stop_in_long", "walk_gate", "warped_look", "down_in_phrase")
"""The spotter's settings this bench takes (`voice_bench.SPOTTER_OPTIONS`)."""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--renderings", type=int, default=8, help="renderings of each phrase and each pair")
    ap.add_argument("--engine", default="spotter")
    ap.add_argument("--workers", type=int, default=2)
    add_spotter_options(ap, SPOTTER_SETTINGS)
    ap.add_argument("--voices", choices=("heldout", "train"), default="heldout",
                    help="who says them: the held-out voices (default) or the head's training voices")
    ap.add_argument("--knowledge", type=Path, default=KNOWLEDGE_FILE,
                    help="the reasoner's knowledge file for its agent and the policy (HRI_REASONER_KNOWLEDGE; "
                         "default: the service's). One Soar kernel per process (REFERENCE.md): to compare two, run "
                         "twice")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    args = ap.parse_args()
    policy = Policy.from_knowledge(args.knowledge)
    pool_voices = corpus.voices(args.voices)
    extra = list(corpus.HELDOUT_EXTRA) if args.voices == "heldout" else []
    missing = tts.unavailable(pool_voices + extra)
    for voice, why in missing.items():
        print(f"left out, cannot speak here: {voice} ({why})", flush=True)
    voices = [v for v in pool_voices + extra if v not in missing]
    rng = random.Random(f"phrases:{args.seed}")
    jobs = [(group, dataset.Recipe(phrase, len(corpus.VOCABULARY), rng.choice(voices), rng.choice((0.85, 1.0, 1.15)),
                                   1.0, rng.randrange(2**31), float(k % 2)))
            for group, (_, phrases) in GROUPS.items() for phrase in phrases for k in range(args.renderings)]
    pair_jobs = [(pair, rng.choice(voices), rng.choice((0.85, 1.0, 1.15)))
                 for pair in PAIRS for _ in range(args.renderings)]
    meant_jobs = [(pair, rng.choice(voices), rng.choice((0.85, 1.0, 1.15)))
                  for pair in MEANT_PAIRS for _ in range(args.renderings)]
    rng_sentences = random.Random(f"sentences:{args.seed}")
    jobs += [(group, dataset.Recipe(text, len(corpus.VOCABULARY), rng_sentences.choice(voices),
                                    rng_sentences.choice((0.85, 1.0, 1.15)), 1.0, rng_sentences.randrange(2**31),
                                    float(k % 2)))
             for group, (_, texts) in SENTENCES.items() for text in texts for k in range(args.renderings)]
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        clips = [c for c in pool.map(_render_phrase, jobs, chunksize=8) if c is not None]
        pairs = [p for p in pool.map(_render_pair, pair_jobs, chunksize=4) if p is not None]
        meant = [p for p in pool.map(_render_pair, meant_jobs, chunksize=4) if p is not None]
    spotter = args.engine == "spotter"
    engine = make_engine(args.engine, **(spotter_settings(args, SPOTTER_SETTINGS) if spotter else {}))
    in_phrase = getattr(engine, "phrase_stop", None) is not None
    in_long = getattr(engine, "long_stop", None) is not None
    print(f"engine {args.engine} (stop within a phrase: {'on' if in_phrase else 'off'}, within a longer utterance: "
          f"{'on' if in_long else 'off'}); reasoner policy {policy}; "
          f"{len(voices)} {args.voices} voices; {len(clips)} of {len(jobs)} phrase clips, {len(pairs)} of "
          f"{len(pair_jobs)} forbidding pairs and {len(meant)} of {len(meant_jobs)} meant pairs rendered\n", flush=True)

    out: dict[str, object] = {"seed": args.seed, "engine": args.engine, "stop_in_phrase": in_phrase,
                              "stop_in_long": in_long, "warped_look": getattr(engine, "warped_look", None) is not None,
                              "down_in_phrase": bool(getattr(getattr(engine, "phrase_stop", None), "others", ())),
                              "voices": len(voices), "voice_split": args.voices,
                              "knowledge": str(args.knowledge)}
    print("One utterance: what the robot heard, per group (clips)")
    by_group: dict[str, dict[str, object]] = {}
    said = [(c, heard(engine.recognise(c.pcm), policy)) for c in clips]
    for group, (should, phrases) in (GROUPS | SENTENCES).items():
        got = Counter(h for c, h in said if c.group == group)
        long = sum(speech_seconds(c.pcm) > MAX_SPEECH_S for c, _ in said if c.group == group)
        per_phrase = {p: dict(Counter(h for c, h in said if c.phrase == p)) for p in phrases}
        by_group[group] = {"should": should, "clips": sum(got.values()), "heard": dict(got), "per_phrase": per_phrase,
                           "longer_than_a_command": long}
        print(f"  {group:28} ({should}): {sum(got.values())} clips ({long} longer than {MAX_SPEECH_S} s), "
              f"{dict(got.most_common())}")
    out["one_utterance"] = by_group

    np_rng = np.random.default_rng(args.seed)
    with SoarAgent(AgentConfig(knowledge_file=args.knowledge)) as agent:
        for title, said_pairs, key_out in (("the first part forbids the \"go\"", pairs, "two_utterances"),
                                           ("the \"go\" is meant", meant, "meant_pairs")):
            print(f"\nTwo utterances, a pause between; {title} (streams: a walk or a question anywhere in the stream, "
                  "utterance by utterance, then by the reasoner's agent over the stream)")
            out[key_out] = {f"{room}, pause {pause * 1000:.0f} ms": _pair_row(
                [stream(spoken_pair(a, b, pause, snr, np_rng), engine) for a, b in said_pairs], agent, policy)
                for room, snr in ROOMS for pause in PAUSES}
            for key, row in out[key_out].items():  # type: ignore[attr-defined]
                print(f"  {key:28} {row['streams']} streams: heard as two utterances {row['heard_as_two']}; "
                      f"utterance by utterance walked {row['walked']}, asked {row['asked']}; the reasoner walked "
                      f"{row['reasoner'][WALKED]}, asked {row['reasoner'][ASKED]}")

    print("\nSentences in a quiet stream (the service's VAD may cut a sentence at its pauses): streams in which an "
          "utterance was heard as \"stop\", as any command")
    sentence_rng = np.random.default_rng([args.seed, 1])  # its own, so that the pairs' streams stay as they were
    out["sentences_streamed"] = {}
    for group in SENTENCES:
        heard_in = [[heard(rec, policy) for rec, _ in stream(in_room(from_pcm(c.pcm), None, sentence_rng), engine)]
                    for c in clips if c.group == group]
        row = {"streams": len(heard_in), "stop": sum("stop" in h for h in heard_in),
               "any_command": sum(any(w != "none" for w in h) for h in heard_in),
               "utterances_per_stream": round(sum(map(len, heard_in)) / max(1, len(heard_in)), 2)}
        out["sentences_streamed"][group] = row  # type: ignore[index]
        print(f"  {group:28} {row['streams']} streams ({row['utterances_per_stream']} utterances each): heard as "
              f"\"stop\" {row['stop']}, as any command {row['any_command']}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
