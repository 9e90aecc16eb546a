"""Voice recognition benchmark on held-out voice families (prints figures; not a test).

The held-out split (`services.voice.training.corpus`) is made by voices the spotter was never trained
or tuned on: flite's rms and slt (two recorded speakers, clustergen), Festival's kal (another
synthesiser), and espeak-ng accents and variants outside training; its non-command words
(`synth.OOV_HELDOUT`) appear in no other split. Each clip is rendered clean and "noisy" (random noise at
3-30 dB SNR, room reverberation, band limits, tempo, as in training but with other seeds), then
trimmed to its speech as the service trims a WAV file.

Besides, the held-out one-edit neighbours of the commands (`corpus.neighbour_split`: dictionary words
one phoneme insertion, deletion or substitution from a command, split off by pronunciation group with
a fixed seed before any training) are each rendered 16 times by random held-out voices, clean or noisy,
and reported in their own row (`one-edit-heldout`), not in "ALL", so that "ALL" stays comparable with
earlier runs. So is each voice of `corpus.HELDOUT_EXTRA` (Festival's HTS slt: the slt speaker through
another synthesiser than flite's; it ignores the speed, so each word is said at its own rate, once clean
and three times noisy).

Per engine and per family: command accuracy (right command published; an "asked" go, i.e. published
with a confidence between the reasoner's `^min-confidence` and `^confirm-below`, counts as right when a
"yes" by the same voice would confirm it, and is reported separately), non-command words accepted, noise
accepted, false walks through the reasoner's policy, real-time factor (decode time / utterance time),
and stream latency (end of speech -> VoiceCommand: the VAD's end-of-utterance decision plus decoding).
With `--enrol`: the figure for five samples per command of an unseen voice (adapting the head `enroll` adapts, the
speech-embedding head, or `--enrol-head H`), who also says the words
`--mic` enrolment prompts (`enrol.PROMPT_OTHERS`, `PROMPT_REPEATS` times each; none is scored), and without those words.

False walks: a non-"go" clip published as "go" at or above `^confirm-below` walks at once ("direct");
one between `^min-confidence` and it makes the robot ask ("false asks"), and walks only if the next
thing heard is a "yes" at `^yes-min-confidence` or more: the bench reports how often non-"yes" speech
is heard so. Thresholds are read from services/reasoner/agent/knowledge.soar (0.5 / 0.85 / 0.7 if absent).

    nice -n 10 .venv/bin/python bench/voice_bench.py                       # spotter + pocketsphinx
    .venv/bin/python bench/voice_bench.py --engines spotter --enrol --json out.json
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import multiprocessing
import os
import pickle
import random
import re
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import resample_poly

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from schemas.messages import Command
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav, rounded_pcm
from services.voice.engine import Engine, make_engine, one_blas_thread
from services.voice.mic import CHUNK_S, ToServiceRate
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.spotter import whisper
from services.voice.training import corpus, dataset, tts

KNOWLEDGE = ROOT / "services/reasoner/agent/knowledge.soar"
WORDS = corpus.VOCABULARY
OTHER = len(WORDS)


WALK, ASK = "go: walk", "go: ask"
"""`Policy.takes` for a "go": the robot walks at once, or asks "Shall I walk forward?" first."""


@dataclass(frozen=True)
class Policy:
    """The reasoner's thresholds for "go" and for the confirming "yes"."""

    min_confidence: float = 0.5
    confirm_below: float = 0.85
    yes_min: float = 0.7

    @classmethod
    def from_knowledge(cls, path: Path = KNOWLEDGE) -> Policy:
        text = path.read_text() if path.exists() else ""
        go = re.search(r"\^word go\b[^)]*", text)
        block = go.group(0) if go else ""

        def num(pattern: str, src: str, default: float) -> float:
            m = re.search(pattern + r"\s+([0-9.]+)", src)
            return float(m.group(1)) if m else default

        return cls(num(r"\^min-confidence", block, 0.5), num(r"\^confirm-below", block, 0.85),
                   num(r"\^yes-min-confidence", text, 0.7))

    def takes(self, command: Command | None, confidence: float) -> str | None:
        """What the reasoner does with one published command, as every voice bench counts it: None if it acts on
        nothing (no command, or below "go"'s `^min-confidence`, which every command is held to here: the others'
        own, 0.3, is below anything the spotter publishes), `WALK` or `ASK` for a "go", else the command's word."""
        if command is None or confidence < self.min_confidence:
            return None
        if command is Command.GO:
            return WALK if confidence >= self.confirm_below else ASK
        return command.value


@dataclass(frozen=True)
class Item:
    family: str
    voice: str
    label: int
    text: str
    condition: str
    pcm: bytes


def family(voice: str) -> str:
    return "espeak-heldout" if voice.startswith("espeak:") else voice


def heldout_recipes(seed: int) -> list[tuple[dataset.Recipe, str]]:
    rng = random.Random(f"bench:{seed}")
    out: list[tuple[dataset.Recipe, str]] = []
    forbidden = corpus.forbidden_negatives()
    oov = [w for w in synth.OOV_HELDOUT if w not in forbidden]
    for voice in corpus.voices("heldout"):
        for cond, strength in (("clean", 0.0), ("noisy", 1.0)):
            speeds = (0.85, 1.15) if not voice.startswith("espeak") else (rng.choice((0.85, 1.0, 1.15)),)
            for speed in speeds:
                for i, word in enumerate(WORDS):
                    out.append((dataset.Recipe(word, i, voice, speed, 1.0, rng.randrange(2**31), strength), cond))
            for word in oov:
                out.append((dataset.Recipe(word, OTHER, voice, rng.choice((0.85, 1.0, 1.15)), 1.0,
                                           rng.randrange(2**31), strength), cond))
    return out


NEIGHBOURS = "one-edit-heldout"
NEIGHBOUR_RENDERINGS = 16
SEPARATE = {NEIGHBOURS, *corpus.HELDOUT_EXTRA}
"""Families reported in their own rows only, not in "ALL"."""


EXTRA_CONDITIONS = (("clean", 0.0), ("noisy", 1.0), ("noisy", 1.0), ("noisy", 1.0))
"""Each `corpus.HELDOUT_EXTRA` voice says each word once clean and three times noisy, at speed 1.0..."""
NEURAL_CONDITIONS = (*EXTRA_CONDITIONS, ("clean", 0.0), ("noisy", 1.0))
"""...but a neural voice (`corpus.HELDOUT_NEURAL`) six times, each at a speed drawn from `NEURAL_SPEEDS`: it says a word
the same way every time at one speed (its noise is off, for reproducible clips)."""
NEURAL_SPEEDS = (0.85, 1.0, 1.15)


def extra_recipes(seed: int) -> list[tuple[dataset.Recipe, str]]:
    """The commands and `OOV_HELDOUT` by each `corpus.HELDOUT_EXTRA` voice: once clean, three times noisy (a neural
    voice: `NEURAL_CONDITIONS`)."""
    rng = random.Random(f"bench-extra:{seed}")
    forbidden = corpus.forbidden_negatives()
    words = [*enumerate(WORDS), *((OTHER, w) for w in synth.OOV_HELDOUT if w not in forbidden)]
    out: list[tuple[dataset.Recipe, str]] = []
    for voice in corpus.HELDOUT_EXTRA:
        neural = voice in corpus.HELDOUT_NEURAL
        for cond, strength in NEURAL_CONDITIONS if neural else EXTRA_CONDITIONS:
            for label, word in words:
                speed = rng.choice(NEURAL_SPEEDS) if neural else 1.0  # no draw for the others: their clips as before
                out.append((dataset.Recipe(word, label, voice, speed, 1.0, rng.randrange(2**31), strength), cond))
    return out


def neighbour_recipes(seed: int) -> list[tuple[dataset.Recipe, str]]:
    """The held-out one-edit neighbours, each said `NEIGHBOUR_RENDERINGS` times by random held-out
    voices (half clean, half noisy)."""
    rng = random.Random(f"bench-neighbours:{seed}")
    voices = corpus.voices("heldout")
    out: list[tuple[dataset.Recipe, str]] = []
    for word in dataset.neighbours(dataset.Sizes(), 12)["heldout"]:
        for k in range(NEIGHBOUR_RENDERINGS):
            cond, strength = ("clean", 0.0) if k % 2 == 0 else ("noisy", 1.0)
            out.append((dataset.Recipe(word, OTHER, rng.choice(voices), rng.choice((0.85, 1.0, 1.15)), 1.0,
                                       rng.randrange(2**31), strength), cond))
    return out


def _render(job: tuple[dataset.Recipe, str]) -> Item | None:
    r, cond = job
    try:
        pcm = dataset.render_utterance(r)
    except tts.TtsError:  # a word this voice cannot say drops the clip (counted; a voice that cannot: _speakable)
        return None
    return Item(family(r.voice), r.voice, r.label, r.text, cond, pcm)


def _speakable(jobs: list[tuple[dataset.Recipe, str]], required: bool) -> list[tuple[dataset.Recipe, str]]:
    """`jobs` whose voice can speak here (`tts.unavailable`). A voice that cannot: SystemExit if `required` (the
    rows every run compares), else said and its row left out (the extra rows: engines from Debian's non-free
    section, wheels of the test extra)."""
    voices = {r.voice for r, _ in jobs}
    if required:
        try:
            tts.require(voices)
        except tts.TtsError as exc:
            raise SystemExit(f"{exc}\n(rows every run compares; what to install: services/voice/README.md)") from None
        return jobs
    missing = tts.unavailable(voices)
    for voice, why in missing.items():
        print(f"left out, cannot speak here: {voice} ({why})", flush=True)
    return [(r, c) for r, c in jobs if tts.base_voice(r.voice) not in missing]


def _rendered(jobs: list[tuple[dataset.Recipe, str]], workers: int, required: bool = True,
              split: str = "heldout") -> list[Item]:
    """The clips of `jobs`, rendered in `workers` processes and cached under `split`'s name (a tuning set's cache is
    never named held-out)."""
    jobs = _speakable(jobs, required)
    key = hashlib.sha1(repr([1, jobs]).encode()).hexdigest()[:16]  # bump when render_utterance changes
    cache = synth.cache_dir() / f"bench-{split}-{key}.pickle"
    if cache.exists():
        items: list[Item] = pickle.loads(cache.read_bytes())
    else:
        with multiprocessing.get_context("spawn").Pool(workers) as pool:
            items = [i for i in pool.map(_render, jobs, chunksize=16) if i is not None]
        tmp = cache.with_suffix(f".{os.getpid()}.tmp")  # whole or not at all: another run may read it meanwhile
        tmp.write_bytes(pickle.dumps(items))
        tmp.replace(cache)
    print(f"{'held-out' if split == 'heldout' else split} clips: {len(items)} of {len(jobs)} rendered", flush=True)
    return items


def through_mic(x: np.ndarray, rate: int | None) -> np.ndarray:
    """`x` (16 kHz, float) as a microphone at `rate` Hz would hand it to the service: the sound sampled at that rate
    (`resample_poly`; the sound itself stays band-limited to 8 kHz), 16-bit, then brought back to 16 kHz by the
    service's own path (`mic.ToServiceRate`, soxr) in 30 ms blocks. None: as it is."""
    if rate is None:
        return x
    g = math.gcd(rate, SAMPLE_RATE)
    pcm = rounded_pcm(np.clip(resample_poly(x, rate // g, SAMPLE_RATE // g), -1.0, 1.0))
    convert, block = ToServiceRate(rate, 1), int(CHUNK_S * rate) * 2
    out = b"".join(c for k in range(0, len(pcm), block) for c in convert(pcm[k : k + block]))
    return np.frombuffer(out, "<i2") / 32768.0


def mic_pcm(pcm: bytes, rate: int | None) -> bytes:
    """A 16 kHz clip as a microphone at `rate` Hz would hand it to the service (`through_mic`), the same length
    (the resampler holds back its last few ms: the clip is padded with silence for it, then cut)."""
    if rate is None:
        return pcm
    x = np.concatenate([np.frombuffer(pcm, "<i2") / 32768.0, np.zeros(int(0.1 * SAMPLE_RATE))])
    return rounded_pcm(through_mic(x, rate)[: len(pcm) // 2])


def through_mic_items(items: list[Item], rate: int | None) -> list[Item]:
    """Every clip, speech and noise, as a microphone at `rate` Hz would hand it to the service (None: as rendered)."""
    return items if rate is None else [replace(it, pcm=mic_pcm(it.pcm, rate)) for it in items]


def heldout_items(seed: int, workers: int) -> list[Item]:
    items = _rendered(heldout_recipes(seed), workers)
    items += [Item(NEIGHBOURS, it.voice, it.label, it.text, it.condition, it.pcm)
              for it in _rendered(neighbour_recipes(seed), workers)]
    for clip in synth.noise_set("heldout"):
        items.append(Item("noise", "", OTHER, clip.text, "noise", read_wav(clip.path)))
    return items + _rendered(extra_recipes(seed), workers, required=False)


@dataclass
class Score:
    engine: str
    family: str
    commands: int = 0
    correct_direct: int = 0
    correct_asked: int = 0
    asked_go: int = 0
    walked_go: int = 0
    """"go" clips the robot walks on at once, without asking (a walk gate that does not hear a voice turns them into
    questions)"""
    oov: int = 0
    oov_accepted: int = 0
    noise: int = 0
    noise_accepted: int = 0
    false_walk_direct: int = 0
    false_ask: int = 0
    decode_s: float = 0.0
    audio_s: float = 0.0
    per_command: dict[str, list[int]] = field(default_factory=lambda: defaultdict(lambda: [0, 0]))
    errors: Counter[str] = field(default_factory=Counter)
    walked_on: Counter[str] = field(default_factory=Counter)

    def row(self) -> dict[str, object]:
        return {
            "engine": self.engine, "family": self.family,
            "command_accuracy": round((self.correct_direct + self.correct_asked) / max(1, self.commands), 3),
            "of_which_asked_and_confirmed": self.correct_asked, "go_asked": self.asked_go, "go_walked": self.walked_go,
            "by_command": {k: round(v[0] / max(1, v[1]), 2) for k, v in self.per_command.items()},
            "oov_accepted": round(self.oov_accepted / max(1, self.oov), 3),
            "noise_accepted": round(self.noise_accepted / max(1, self.noise), 3),
            "false_walks_direct": self.false_walk_direct, "false_asks": self.false_ask,
            "rtf": round(self.decode_s / max(1e-9, self.audio_s), 4),
            "n": {"commands": self.commands, "oov": self.oov, "noise": self.noise},
            "top_errors": dict(self.errors.most_common(8)),
            "false_walks_on": dict(self.walked_on.most_common(10)),
        }


def score(engine_name: str, engine: Engine, items: list[Item], policy: Policy) -> tuple[list[Score], dict]:
    results = {}
    for idx, item in enumerate(items):
        t0 = time.perf_counter()
        rec = engine.recognise(item.pcm)
        dt = time.perf_counter() - t0
        results[idx] = (rec.command, rec.confidence, dt)
    # The "yes" that would confirm an asked go: the same voice and condition's "yes" clip.
    yes_conf = {(it.voice, it.condition): results[i][1] for i, it in enumerate(items)
                if it.label == WORDS.index("yes") and results[i][0] == Command.YES}
    non_yes_confident = sum(1 for i, it in enumerate(items) if it.label != WORDS.index("yes")
                            and results[i][0] == Command.YES and results[i][1] >= policy.yes_min)
    non_yes = sum(1 for it in items if it.label != WORDS.index("yes"))
    scores: dict[str, Score] = {}
    for i, it in enumerate(items):
        cmd, conf, dt = results[i]
        for fam in (it.family,) if it.family in SEPARATE else (it.family, "ALL"):
            s = scores.setdefault(fam, Score(engine_name, fam))
            s.decode_s += dt
            s.audio_s += len(it.pcm) / 2 / SAMPLE_RATE
            taken = policy.takes(cmd, conf)
            walks, asks = taken == WALK, taken == ASK
            if it.label != WORDS.index("go") and walks:
                s.false_walk_direct += 1
                s.walked_on[f"{it.text} ({it.voice}, {it.condition})"] += 1
            if it.label != WORDS.index("go") and asks:
                s.false_ask += 1
            if it.label < OTHER:
                word = WORDS[it.label]
                s.commands += 1
                s.per_command[word][1] += 1
                ok = taken is not None and cmd is not None and cmd.value == word
                if ok and word == "go" and asks:
                    s.asked_go += 1
                    ok = yes_conf.get((it.voice, it.condition), 0.0) >= policy.yes_min
                    s.correct_asked += ok
                else:
                    s.correct_direct += ok
                    s.walked_go += ok and word == "go" and walks
                s.per_command[word][0] += ok
                if not ok:
                    s.errors[f"{word}->{cmd.value if cmd else 'none'}"] += 1
            elif it.family == "noise":
                s.noise += 1
                s.noise_accepted += cmd is not None
            else:
                s.oov += 1
                s.oov_accepted += cmd is not None
                if cmd is not None:
                    s.errors[f"{it.text}->{cmd.value}"] += 1
    extra = {"non_yes_heard_as_confident_yes": f"{non_yes_confident}/{non_yes}"}
    return list(scores.values()), extra


def loud_frames(x: np.ndarray, floor_db: float, eps: float = 1e-9) -> np.ndarray:
    """The indices of `x`'s 10 ms frames (160 samples) whose power is within `floor_db` of its loudest frame's
    (`eps` is added to each frame's mean power before the logarithm)."""
    frames = x[: x.size // 160 * 160].reshape(-1, 160)
    level = 10 * np.log10(np.mean(frames**2, axis=1) + eps)
    return np.flatnonzero(level >= level.max() - floor_db)


def speech_end_s(pcm: bytes, floor_db: float = 30.0) -> float:
    """Where a clip's speech ends (s): the end of its last 10 ms frame within `floor_db` of its loudest frame.
    (Not the clip's end minus the post-roll: the clip was trimmed by WebRTC's VAD, whose end lags the voice's
    by its window, so a VAD that ends sooner would seem to answer before the speech ended.)"""
    loud = loud_frames(np.frombuffer(pcm, "<i2").astype(np.float64), floor_db)
    return float((loud[-1] + 1) * 160 / SAMPLE_RATE) if loud.size else len(pcm) / 2 / SAMPLE_RATE


def stream_latency(engine: Engine, items: list[Item], n: int = 40,
                   config: SegmenterConfig | None = None, mic_rate: int | None = None) -> dict[str, float]:
    """End of speech -> command, on a stream: each clip in quiet noise, fed in 30 ms chunks to the
    service's VAD segmenter (with the engine for its early look, as the service); latency = audio time at which
    the segment is emitted - the clip's speech end (`speech_end_s`), plus decoding time (for a segment the early
    look took: the time of the chunk's `feed`, which decoded it). `mic_rate`: the stream, speech and hiss, as a
    microphone at that rate would hand it to the service (`through_mic`)."""
    rng = np.random.default_rng(5)
    clean = [it for it in items if it.label < OTHER and it.condition == "clean"]
    picks = clean[:: max(1, len(clean) // n)][:n]  # n spread over the clean commands (before: a stride over all
    # items, which left 14 of the 40 asked for)
    lat = []
    taken = 0
    for it in picks:
        lead = np.zeros(int(0.8 * SAMPLE_RATE))
        x = np.concatenate([lead, np.frombuffer(it.pcm, "<i2") / 32768.0, np.zeros(SAMPLE_RATE)])
        x = x + rng.normal(0, 3e-4, x.size)
        speech_end = lead.size / SAMPLE_RATE + speech_end_s(it.pcm)
        pcm = rounded_pcm(through_mic(x, mic_rate))
        seg = Segmenter(config or SegmenterConfig(), recognise=engine.recognise)
        step = int(0.03 * SAMPLE_RATE) * 2
        for k in range(0, len(pcm), step):
            t0 = time.perf_counter()
            found = seg.feed(pcm[k : k + step])
            if found:
                t_emit = (k + step) / 2 / SAMPLE_RATE
                if found[0].recognition is None:
                    t0 = time.perf_counter()
                    engine.recognise(found[0].pcm)
                taken += found[0].recognition is not None
                lat.append(t_emit - speech_end + time.perf_counter() - t0)
                break
    a = np.array(lat) * 1000
    return {"n": len(a), "p50_ms": round(float(np.median(a)), 1), "p90_ms": round(float(np.percentile(a, 90)), 1),
            "max_ms": round(float(a.max()), 1), "early_taken": taken}


SPOTTER_OPTIONS = {
    "walk_gate": "the spotter's walk gate: a head file or none (HRI_VOICE_WALK_GATE; default: the engine's)",
    "agree_min": "the spotter's agreement veto (HRI_VOICE_AGREE_MIN; default: the engine's)",
    "decoder": "the spotter's second opinion from Whisper's decoder, on or off (HRI_VOICE_DECODER; default: the "
               "engine's)",
    "stop_in_phrase": "the spotter also hears \"stop\" within a phrase, on or off (HRI_VOICE_STOP_IN_PHRASE; "
                      "default: the engine's)",
    "stop_in_long": "the spotter also hears \"stop\" within an utterance longer than 1.7 s, on or off "
                    "(HRI_VOICE_STOP_IN_LONG; default: the engine's)",
    "down_in_phrase": "the spotter also hears \"down\" within a phrase (\"sit down\"), on or off "
                      "(HRI_VOICE_DOWN_IN_PHRASE; default: the engine's)",
    "warped_look": "the spotter's second look, at other speeds, of an utterance it came near to accepting, on or off "
                   "(HRI_VOICE_WARPED_LOOK; default: the engine's)",
}
"""The spotter's settings a bench takes as options (`--walk-gate`, ...): each a `make_engine` keyword, with its
help."""


def add_spotter_options(ap: argparse.ArgumentParser, names: Iterable[str]) -> None:
    """`--walk-gate`, `--stop-in-phrase`, ... for the spotter settings `names` (keys of `SPOTTER_OPTIONS`)."""
    for name in names:
        ap.add_argument("--" + name.replace("_", "-"), help=SPOTTER_OPTIONS[name])


def spotter_settings(args: argparse.Namespace, names: Iterable[str]) -> dict[str, str | None]:
    """The `make_engine` keywords of the spotter settings `names`, as the options gave them (None: the engine's)."""
    return {name: getattr(args, name) for name in names}


def early_look_arg(text: str) -> float | None:
    """A bench option that takes a number or `off` (None): `--early-look`, `--clear-window`, `--vad-lift`,
    `--vad-lift-floor`, `voice_long_stream.py --resets`."""
    return None if text.strip().lower() == "off" else float(text)


def add_lift_options(ap: argparse.ArgumentParser) -> None:
    """The live stream's VAD lift (`SegmenterConfig.vad_lift_*`) and high-pass (`highpass_hz`), for the benches that run
    the service's segmenter; each defaults to the service's."""
    ap.add_argument("--vad-lift", type=early_look_arg, default=SegmenterConfig.vad_lift_dbfs,
                    help="Silero: the peak the VAD hears the loudest frame lifted to, dBFS, or off (default: the service's)")
    ap.add_argument("--vad-lift-floor", type=early_look_arg, default=SegmenterConfig.vad_lift_floor_dbfs,
                    help="with --vad-lift: the level (dBFS RMS) the lift never brings the noise floor over, or off "
                         "(default: the service's)")
    ap.add_argument("--vad-lift-second", action=argparse.BooleanOptionalAction, default=SegmenterConfig.vad_lift_second,
                    help="with --vad-lift: a second VAD hears the lifted stream, its utterances counted only where the "
                         "first heard nothing (default: the service's)")
    ap.add_argument("--vad-lift-hold", type=float, default=SegmenterConfig.vad_lift_hold_s,
                    help="with --vad-lift-second: seconds the second VAD's utterance waits, dropped if the first starts "
                         "one meanwhile (default: the service's)")
    ap.add_argument("--highpass", type=early_look_arg, default=SegmenterConfig.highpass_hz,
                    help="the stream's high-pass (Hz), switched on by a DC offset, or off (SegmenterConfig.highpass_hz; "
                         "default: the service's)")
    ap.add_argument("--highpass-dc-share", type=float, default=SegmenterConfig.highpass_dc_share,
                    help="with --highpass: the share of the power outside utterances a DC offset must carry to switch "
                         "it on (SegmenterConfig.highpass_dc_share; 0: its mean alone; default: the service's)")


def lift_settings(args: argparse.Namespace) -> dict[str, Any]:
    """`add_lift_options`' values as `SegmenterConfig` keywords."""
    return {"vad_lift_dbfs": args.vad_lift, "vad_lift_floor_dbfs": args.vad_lift_floor,
            "vad_lift_second": args.vad_lift_second, "vad_lift_hold_s": args.vad_lift_hold,
            "highpass_hz": args.highpass, "highpass_dc_share": args.highpass_dc_share}


def enrol_figure(items: list[Item], head_path: str | None, voice: str = "flite:slt") -> dict[str, object]:
    """Five samples per command of one held-out voice (speed 1.0, clean and noisy renderings made for
    this) and, as `--mic` prompts them, the words of `enrol.PROMPT_OTHERS` `PROMPT_REPEATS` times each (clean;
    none of them is a scored word), then the held-out clips of that voice before and after. Also the enrolment without the
    prompted words (the recipe before round 9), on the same samples."""
    from services.voice.engine_spotter import SpotterEngine
    from services.voice.enrol import PROMPT_OTHERS, PROMPT_REPEATS, adapt
    from services.voice.spotter.head import SPEECH_EMBEDDING_HEAD, Head

    rng = random.Random(3)
    samples = []
    for i, word in enumerate(WORDS):
        for k in range(5):
            r = dataset.Recipe(word, i, voice, rng.uniform(0.9, 1.1), rng.uniform(0.9, 1.1), 10_000 + 7 * i + k,
                               0.0 if k < 3 else 1.0)
            samples.append((word, dataset.render_utterance(r)))
    mine_others = []
    for k in range(PROMPT_REPEATS):
        for j, word in enumerate(PROMPT_OTHERS):
            r = dataset.Recipe(word, OTHER, voice, rng.uniform(0.9, 1.1), rng.uniform(0.9, 1.1), 20_000 + 100 * k + j, 0.0)
            mine_others.append(("other", dataset.render_utterance(r)))
    scored = {it.text for it in items if it.family != "noise"}  # a noise clip's text is its kind ("white")
    if scored & set(PROMPT_OTHERS):  # by construction (corpus rule, tested): enrolment words are never scored
        raise RuntimeError(f"prompted enrolment words among the scored clips: {sorted(scored & set(PROMPT_OTHERS))}")
    base = Head.load(head_path or SPEECH_EMBEDDING_HEAD)  # as `enroll` does
    t0 = time.perf_counter()
    enrolled = adapt(base, samples + mine_others)
    adapt_s = time.perf_counter() - t0
    without = adapt(base, samples)
    mine = [it for it in items if it.voice == voice]
    out: dict[str, object] = {"voice": voice, "samples_per_command": 5, "prompted_others": len(mine_others),
                              "adapt_s": round(adapt_s, 1)}
    policy = Policy.from_knowledge()
    for name, head in (("before", base), ("after", enrolled), ("after_without_prompted_others", without)):
        scores, _ = score("spotter", SpotterEngine(head), mine, policy)
        own = voice if voice in SEPARATE else "ALL"  # a voice of its own row (a neural one) is outside "ALL"
        row = next(s for s in scores if s.family == own).row()
        out[name] = {k: row[k] for k in ("command_accuracy", "oov_accepted", "false_walks_direct", "false_asks")}
    others = [it for it in items if it.voice != voice and it.family not in ("noise", *corpus.HELDOUT_EXTRA)][::3]
    for name, head in (("after_on_other_voices", enrolled), ("without_prompted_others_on_other_voices", without)):
        scores, _ = score("spotter", SpotterEngine(head), others, policy)
        row = next(s for s in scores if s.family == "ALL").row()
        out[name] = {k: row[k] for k in ("command_accuracy", "oov_accepted", "false_walks_direct")}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engines", default="spotter,pocketsphinx")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--enrol", action="store_true", help="also measure enrolment on one unseen voice")
    ap.add_argument("--json", type=Path, help="also write the rows here")
    ap.add_argument("--head", help="spotter head file (default: the committed default head)")
    add_spotter_options(ap, SPOTTER_OPTIONS)
    ap.add_argument("--vad", default=SegmenterConfig.vad, help="the stream latency's VAD (default: the service's)")
    ap.add_argument("--early-look", type=early_look_arg, default=SegmenterConfig.early_quiet_s,
                    help="the stream latency's early look: seconds of quiet, or off (default: the service's)")
    ap.add_argument("--clear-window", type=early_look_arg, default=SegmenterConfig.clear_quiet_s,
                    help="the stream latency's end window in a clear stream: seconds of quiet, or off (default: the service's)")
    ap.add_argument("--enrol-head", help="the head --enrol adapts (default: as `enroll`, the speech-embedding head)")
    ap.add_argument("--mic-rate", type=int,
                    help="every clip, and the stream latency's stream, as a microphone at this rate (Hz) would hand it "
                         "to the service, resampled by its own path (`mic.ToServiceRate`; default: as rendered)")
    ap.add_argument("--enrol-voice", default="flite:slt",
                    help="the unseen voice --enrol enrols, a held-out voice (e.g. piper:en_US-joe-medium, a neural one)")
    args = ap.parse_args()
    policy = Policy.from_knowledge()
    print(f"reasoner policy: {policy}; BLAS threads {one_blas_thread()}, as in the voice service", flush=True)
    arithmetic = {"compute": whisper.compute_type(), "int8_exact": whisper.exact_int8()}
    print(f"Whisper (the default head's embedding) in {arithmetic['compute']}; this CPU's int8 sums "
          + ("exactly (VNNI)" if arithmetic["int8_exact"] else "with saturation, as the committed default head was fitted")
          + " (docs/experiments/voice-rounds.md, stop 67)", flush=True)
    rendered = heldout_items(args.seed, args.workers)
    items = through_mic_items(rendered, args.mic_rate)
    if args.mic_rate:
        print(f"every clip through a microphone at {args.mic_rate} Hz and the service's resampler", flush=True)
    rows: list[dict[str, object]] = []
    for name in args.engines.split(","):
        spotter = name == "spotter"
        engine = make_engine(name, head_path=args.head if spotter else None,
                             **(spotter_settings(args, SPOTTER_OPTIONS) if spotter else {}))
        scores, extra = score(name, engine, items, policy)
        for s in sorted(scores, key=lambda s: (s.family != "ALL", s.family)):
            row = s.row()
            if s.family == "ALL":
                row.update(extra)
                if spotter:
                    row["whisper"] = arithmetic  # the figures depend on it (stop 67)
                    row["mic_rate"] = args.mic_rate
                row["stream_latency"] = stream_latency(engine, [it for it in rendered if it.family not in corpus.HELDOUT_EXTRA],
                                                       config=SegmenterConfig(vad=args.vad, early_quiet_s=args.early_look,
                                                                              clear_quiet_s=args.clear_window),
                                                       mic_rate=args.mic_rate)
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.enrol:
        enrol = enrol_figure(items, args.enrol_head, args.enrol_voice)
        rows.append({"enrolment": enrol})
        print(json.dumps({"enrolment": enrol}), flush=True)
    print()
    print(f"{'engine':13} {'family':24} {'cmd acc':>7} {'asked':>5} {'OOV acc':>7} {'noise':>6} {'walks':>5} "
          f"{'f.asks':>6} {'RTF':>7}")
    for r in rows:
        if "engine" in r:
            print(f"{r['engine']:13} {r['family']:24} {r['command_accuracy']:7.3f} {r['of_which_asked_and_confirmed']:5d} "
                  f"{r['oov_accepted']:7.3f} {r['noise_accepted']:6.3f} {r['false_walks_direct']:5d} "
                  f"{r['false_asks']:6d} {r['rtf']:7.4f}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
