"""Words said now and then into one long stream, as a running voice service hears them (prints figures; not a test).

Every other stream bench starts a new stream (and a new VAD) for each word, with a second or less of room before it.
The service hears one stream for as long as it runs; Silero VAD carries its state from frame to frame, and that state
drifts over a long stream (stop 91: after 30 s of a quiet room a word's end is found 0.5 s late). This bench says
what that costs and what `SegmenterConfig.vad_reset_s` buys:

- words: `--seed S`: the clean held-out clips of `voice_bench`'s seed S (other voices and engines than the tuning's;
  commands and other words, `--n` of each at most, drawn with the seed); `--tuning`: the tuning split's voices
  (`corpus.voices("tune")`) saying the commands and `synth.OOV_TUNE`, clean;
- each word trimmed to its speech, brought to each `--peaks` level (dBFS peak), and said into one stream of a quiet
  room's hiss (`--floor` dBFS RMS) after a pause drawn from 1 to `--longest` s (the same words, order and pauses for
  every way);
- the stream rounded to 16 bits as a sound card does (`rounded_pcm`), through a microphone's path at `--mic-rate` if
  asked (`voice_bench.through_mic`), then through the service's path (`sources.stream_utterances`: high-pass, Silero
  VAD with the lifted second VAD, end windows; 30 ms chunks) and the engine, each way of `--resets` (`default`: the
  service's; `off`: one state, never restarted; `vad_reset_s` in seconds; `fresh<s>[:<dB>]`: `vad_fresh_end_s` and
  `vad_fresh_end_snr_db`);
- a command counts as heard when an utterance overlapping its word is taken by the reasoner's policy
  (`voice_bench.Policy`) as that command (a "go" asked about counts); another word counts as accepted when an
  overlapping utterance is taken as any command; latency: from the word's speech end to the stream time at which
  its utterance was handed over, plus the decoding (as `voice_bench.stream_latency`); a false walk: a word other
  than "go" (a command or not) that an overlapping utterance makes the robot walk on at once;
- each way after the first: word by word against the first (`against_first_way`: commands lost and gained, other
  words newly taken and no longer taken), the count a pooled rule's tolerance is set from (stop 94); `--json` also
  keeps which words each way heard (`heard_at`, `accepted_at`: positions in the stream).

    .venv/bin/python bench/voice_long_stream.py --tuning
    .venv/bin/python bench/voice_long_stream.py --seed 23281 --json out.json
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import (  # noqa: E402
    OTHER,
    WALK,
    WORDS,
    Item,
    Policy,
    _rendered,
    early_look_arg,
    heldout_items,
    loud_frames,
    speech_end_s,
    through_mic,
)
from bench.voice_levels import at_level  # noqa: E402
from services.voice import synth  # noqa: E402
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH, rounded_pcm, to_pcm  # noqa: E402
from services.voice.engine import Engine, Recognition, make_engine, one_blas_thread  # noqa: E402
from services.voice.mic import CHUNK_S  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402
from services.voice.sources import stream_utterances  # noqa: E402
from services.voice.training import corpus, dataset  # noqa: E402

SHORTEST_S = 1.0


def tuning_items(seed: int) -> list[Item]:
    """The tuning split's voices saying each command and each `synth.OOV_TUNE` word once, clean, at a speed drawn."""
    rng = random.Random(f"long-stream-tune:{seed}")
    words = [*enumerate(WORDS), *((OTHER, w) for w in synth.OOV_TUNE)]
    jobs = [(dataset.Recipe(word, label, voice, rng.choice((0.85, 1.0, 1.15)), 1.0, rng.randrange(2**31), 0.0),
             "clean") for voice in corpus.voices("tune") for label, word in words]
    return _rendered(jobs, workers=2, required=False, split="tuning")


def picked(items: list[Item], n: int, seed: int) -> list[Item]:
    """Up to `n` clean commands and `n` clean other words, drawn with `seed`, in a drawn order."""
    rng = random.Random(f"long-stream:{seed}")
    clean = [it for it in items if it.condition == "clean" and it.family != "noise"]
    commands = [it for it in clean if it.label < OTHER]
    others = [it for it in clean if it.label == OTHER]
    out = rng.sample(commands, min(n, len(commands))) + rng.sample(others, min(n, len(others)))
    rng.shuffle(out)
    return out


@dataclass
class Placed:
    item: Item
    start_s: float
    end_s: float
    """Where its speech ends in the stream (`voice_bench.speech_end_s`)."""


def long_stream(items: list[Item], peak: float, floor: float, longest: float, seed: int,
                mic_rate: int | None = None) -> tuple[bytes, list[Placed]]:
    """The words, each trimmed to its speech and at `peak` dBFS, with pauses of `SHORTEST_S` to `longest` s of hiss
    at `floor` dBFS before each (and after the last); rounded to 16 bits as a sound card does, through a microphone's
    path at `mic_rate` (`voice_bench.through_mic`; None: as made)."""
    rng = np.random.default_rng(seed)
    parts, placed, at = [], [], 0
    for it in items:
        x = np.frombuffer(it.pcm, "<i2") / 32768.0
        loud = loud_frames(x, 40.0)
        x = at_level(x[loud[0] * 160 : (loud[-1] + 1) * 160] if loud.size else x, peak)
        pause = int(rng.uniform(SHORTEST_S, longest) * SAMPLE_RATE)
        parts += [np.zeros(pause), x]
        at += pause
        placed.append(Placed(it, at / SAMPLE_RATE, at / SAMPLE_RATE + speech_end_s(to_pcm(np.clip(x, -1, 1)))))
        at += x.size
    parts.append(np.zeros(int(longest * SAMPLE_RATE)))
    stream = np.concatenate(parts)
    stream += rng.normal(0.0, 10 ** (floor / 20), stream.size)
    return rounded_pcm(through_mic(np.clip(stream, -1.0, 1.0), mic_rate)), placed


@dataclass(frozen=True)
class Hearing:
    """One utterance of the stream, as the service hears it."""

    start_s: float
    end_s: float
    recognition: Recognition
    emitted_s: float
    """Stream time at which it was handed over, plus its decoding (the latency point)."""
    snr_db: float | None


def hearings(engine: Engine, pcm: bytes, config: SegmenterConfig) -> list[Hearing]:
    """The stream through the service's path with `config`, in 30 ms chunks: every utterance and its recognition."""
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    fed = [0]

    def chunks():  # type: ignore[no-untyped-def]
        for k in range(0, len(pcm), step):
            fed[0] = k + step
            yield pcm[k : k + step]

    out = []
    for u in stream_utterances(chunks(), "long", config, recognise=engine.recognise):
        began = time.perf_counter()
        rec = u.recognition or engine.recognise(u.pcm)
        emitted = fed[0] / SAMPLE_WIDTH / SAMPLE_RATE + time.perf_counter() - began
        start = u.start_s or 0.0
        out.append(Hearing(start, start + u.seconds, rec, emitted, u.snr_db))
    return out


def heard(engine: Engine, pcm: bytes, placed: list[Placed], config: SegmenterConfig,
          policy: Policy) -> dict[str, object]:
    """The stream through the service's path with `config`: commands heard, other words accepted, latency."""
    # start, end, what the policy takes, latency point (s)
    taken = [(h.start_s, h.end_s, policy.takes(h.recognition.command, h.recognition.confidence), h.emitted_s)
             for h in hearings(engine, pcm, config)]
    commands = [p for p in placed if p.item.label < OTHER]
    others = [p for p in placed if p.item.label == OTHER]
    heard_at, accepted_at, walks, lat = [], [], 0, []
    for k, p in enumerate(placed):
        over = [t for t in taken if t[0] < p.end_s + 0.15 and t[1] > p.start_s]
        walks += p.item.label != WORDS.index("go") and any(t[2] == WALK for t in over)
        if p.item.label < OTHER:
            word = WORDS[p.item.label]
            hits = [t for t in over if t[2] is not None and (t[2] == word or t[2].startswith(f"{word}:"))]
            if hits:
                heard_at.append(k)
                lat.append(hits[0][3] - p.end_s)
        elif any(t[2] is not None for t in over):
            accepted_at.append(k)
    a = np.array(lat) * 1000.0
    right, accepted = len(heard_at), len(accepted_at)
    return {"commands": len(commands), "heard": right, "command_share": round(right / max(1, len(commands)), 3),
            "others": len(others), "others_accepted": accepted,
            "others_share": round(accepted / max(1, len(others)), 3), "false_walks": walks, "utterances": len(taken),
            "latency_p50_ms": round(float(np.median(a)), 1) if a.size else None,
            "latency_p90_ms": round(float(np.percentile(a, 90)), 1) if a.size else None,
            "latency_max_ms": round(float(a.max()), 1) if a.size else None,
            "heard_at": heard_at, "accepted_at": accepted_at}


def disagreement(base: dict[str, object], row: dict[str, object]) -> dict[str, int]:
    """Word by word, how `row`'s way differs from `base`'s on the same stream: commands it lost and gained, other
    words it took and let go. A change of where words are cut flips borderline verdicts both ways; the two counts
    together say how far its net change can move by chance (stop 94's rule: about the square root of their sum)."""
    def diff(key: str) -> tuple[int, int]:
        a, b = set(base[key]), set(row[key])  # type: ignore[call-overload]
        return len(a - b), len(b - a)

    lost, gained = diff("heard_at")
    dropped, taken = diff("accepted_at")
    return {"commands_lost": lost, "commands_gained": gained, "others_newly_taken": taken,
            "others_no_longer_taken": dropped}


def way_config(way: str) -> SegmenterConfig:
    """`default` (the service's), `off` (one state, never restarted: the default before round voice50d), `<s>`
    (`vad_reset_s`), `fresh<s>` (`vad_fresh_end_s`, ending every utterance the fresh state heard) or `fresh<s>:<dB>`
    (ending those with speech that far over the noise: `vad_fresh_end_snr_db`; `fresh1:30` is the default since round
    voice50d) over the defaults."""
    if way == "default":
        return SegmenterConfig()
    if way.startswith("fresh"):
        seconds, _, snr = way.removeprefix("fresh").partition(":")
        return replace(SegmenterConfig(), vad_reset_s=None, vad_fresh_end_s=early_look_arg(seconds),
                       vad_fresh_end_snr_db=float(snr) if snr else None)
    return replace(SegmenterConfig(), vad_reset_s=early_look_arg(way), vad_fresh_end_s=None, vad_fresh_end_snr_db=None)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    source = ap.add_mutually_exclusive_group(required=True)
    source.add_argument("--seed", type=int, help="voice_bench's held-out seed whose clean clips are said")
    source.add_argument("--tuning", action="store_true", help="the tuning split's voices instead")
    ap.add_argument("--n", type=int, default=150, help="commands, and other words, at most")
    ap.add_argument("--peaks", default="-20,-38", help="dBFS peak of every word, a stream each")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss, dBFS RMS")
    ap.add_argument("--longest", type=float, default=20.0, help="the longest pause before a word, s")
    ap.add_argument("--resets", default="off,default",
                    help="the ways: default (the service's), off (one state, never restarted), vad_reset_s in "
                         "seconds, or fresh<seconds>[:<dB>] for vad_fresh_end_s [and vad_fresh_end_snr_db]")
    ap.add_argument("--mic-rate", type=int, help="the stream through a microphone's path at this rate (Hz)")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    print(f"BLAS threads {one_blas_thread()}, as in the voice service", flush=True)
    seed = 0 if args.tuning else args.seed
    items = picked(tuning_items(seed) if args.tuning else heldout_items(args.seed, 2), args.n, seed)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    rows = []
    for peak in (float(p) for p in args.peaks.split(",")):
        pcm, placed = long_stream(items, peak, args.floor, args.longest, seed, args.mic_rate)
        first: dict[str, object] | None = None
        for way in args.resets.split(","):
            config = way_config(way)
            row = {"source": "tuning" if args.tuning else f"held-out seed {args.seed}", "peak_dbfs": peak,
                   "floor_dbfs": args.floor, "mic_rate": args.mic_rate,
                   "stream_min": round(len(pcm) / SAMPLE_WIDTH / SAMPLE_RATE / 60, 1),
                   "vad_reset_s": config.vad_reset_s, "vad_fresh_end_s": config.vad_fresh_end_s,
                   "vad_fresh_end_snr_db": config.vad_fresh_end_snr_db, **heard(engine, pcm, placed, config, policy)}
            if first is None:
                first = row
            else:
                row["against_first_way"] = disagreement(first, row)
            rows.append(row)
            print(json.dumps({k: v for k, v in row.items() if not k.endswith("_at")}), flush=True)  # lists: --json
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
