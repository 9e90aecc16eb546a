"""A command said to a walking robot: the live stream path (VAD segmenter -> engine) in the robot's own
noise (prints figures; not a test).

The held-out bench (`voice_bench.py`) mixes random noise into each clip, then trims it: it never asks
whether the service's voice activity detector still finds the end of a word while the servos whine and
the feet land without pause. This bench does. Each held-out clip (clean renderings of `voice_bench`'s
held-out split, all voice families, the same seed's cache) is placed 1.2 s into a stream of the walking
robot's ego-noise (`ego_noise.py`: a model made from the motion service's gait, or `--noise-wav`, a
recording of your own robot; `--standing`: the robot standing still, only its fan and the servos' holding
hiss), scaled to a speech-to-noise ratio, followed by 1.5 s more of it, and fed to
the service's `Segmenter` in 30 ms chunks (with the engine for its early look when `--early-look S` turns it on;
off by default, as in the service); every segment it emits goes to the engine, as in the service.

Per ratio: commands heard right (the segment that overlaps the word gives its command, accepted; for "go",
at least the reasoner's `^min-confidence`), "stop" on its own (what a walking robot must hear), non-command
words taken for a command (false walks: for a "go" sure enough that the reasoner walks unasked), how many
segments the stream gave and how long they were (a VAD stuck in "speech" cuts at
`SegmenterConfig.max_utterance_s`, and the spotter refuses utterances over its limit), end of speech ->
segment emitted, and commands heard in the noise alone (`--noise-only` seconds of it, no speech). `--dc` adds a
microphone's DC offset to every stream; `--noise-seed` draws the noise again over the same words (a twin run, to see
how far a row moves by chance; `voice_walking.paired` counts the words two runs disagree on).

    nice -n 10 .venv/bin/python bench/voice_walking.py                      # 20, 10, 5, 0 dB and quiet
    .venv/bin/python bench/voice_walking.py --snr 10 --per-family 40 --json out.json
    .venv/bin/python bench/voice_walking.py --standing                     # the robot standing still
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.ego_noise import EgoNoiseModel, ego_noise, mix, unit_rms  # noqa: E402
from bench.voice_bench import (  # noqa: E402
    OTHER,
    WALK,
    WORDS,
    Item,
    Policy,
    add_lift_options,
    early_look_arg,
    heldout_items,
    lift_settings,
    speech_end_s,
    through_mic,
)
from schemas.messages import Command  # noqa: E402
from services.voice.audio import SAMPLE_RATE, read_wav, rounded_pcm  # noqa: E402
from services.voice.engine import Engine, make_engine  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402
from services.voice.training.augment import active_power  # noqa: E402

LEAD_S = 1.2
TAIL_S = 1.5
CHUNK = int(0.03 * SAMPLE_RATE) * 2


def pick(items: list[Item], per_family: int, seed: int) -> list[Item]:
    """Clean clips, commands and non-commands, up to `per_family` of each kind per family."""
    rng = np.random.default_rng(seed)
    out: list[Item] = []
    for fam in sorted({it.family for it in items if it.family != "noise"}):
        for is_cmd in (True, False):
            pool = [it for it in items if it.family == fam and it.condition == "clean" and (it.label < OTHER) == is_cmd]
            take = rng.permutation(len(pool))[:per_family]
            out += [pool[i] for i in sorted(take)]
    return out


def noise_source(seconds: float, rng: np.random.Generator, recording: np.ndarray | None,
                 model: EgoNoiseModel | None = None) -> np.ndarray:
    """`seconds` of the robot's noise at unit RMS: the model's (walking by default), or a stretch of `recording`."""
    if recording is None:
        return ego_noise(seconds, rng, model or EgoNoiseModel())
    n = int(seconds * SAMPLE_RATE)
    start = int(rng.integers(0, max(1, recording.size - n)))
    return unit_rms(np.resize(recording[start:], n))


def stream(engine: Engine, x: np.ndarray, config: SegmenterConfig, switched: Counter[str] | None = None,
           robot: np.ndarray | None = None) -> list[tuple[float, float, float, Command | None, float]]:
    """Feed `x` (float, ±1) to a fresh segmenter in 30 ms chunks: (emitted at s, start s, end s, command,
    confidence) per segment. `switched`: counts the stream under "highpass_on" if the high-pass was switched on.
    `robot`: per sample of `x`, whether the echo canceller said the robot's voice lay there (`Segmenter.feed`'s
    `robot`, for a chunk with any such sample)."""
    pcm = rounded_pcm(x)
    seg = Segmenter(config, recognise=engine.recognise)  # the early look, as in the service
    out = []
    for k in range(0, len(pcm), CHUNK):
        near = robot is not None and bool(np.any(robot[k // 2 : (k + CHUNK) // 2]))
        for s in seg.feed(pcm[k : k + CHUNK], near):
            rec = s.recognition or engine.recognise(s.pcm)
            out.append(((k + CHUNK) / 2 / SAMPLE_RATE, s.start_s, s.end_s, rec.command, rec.confidence))
    for s in seg.flush():
        rec = engine.recognise(s.pcm)
        out.append((len(pcm) / 2 / SAMPLE_RATE, s.start_s, s.end_s, rec.command, rec.confidence))
    if switched is not None:
        switched["highpass_on"] += seg.highpass_on
    return out


Noise = Callable[[float, np.random.Generator], np.ndarray]
"""Seconds -> the robot's noise at unit RMS (`noise_source` with its model or recording)."""


def run_ratio(engine: Engine, clips: list[Item], snr: float | None, config: SegmenterConfig, policy: Policy, seed: int,
              noise: Noise, mic_rate: int | None = None, dc: float = 0.0) -> dict[str, object]:
    """Each clip `LEAD_S` into `noise` at `snr` dB (None: a faint hiss), then `TAIL_S` more: `run_streams`' row.
    `mic_rate`: each stream as a microphone at that rate would hand it to the service (`through_mic`), with its DC
    offset `dc` (a fraction of full scale)."""

    def build(speech: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return through_mic(heard(speech, rng), mic_rate) + dc

    def heard(speech: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        at = int(LEAD_S * SAMPLE_RATE)
        seconds = LEAD_S + speech.size / SAMPLE_RATE + TAIL_S
        if snr is None:  # quiet, as voice_bench's stream latency: a faint hiss
            x = np.zeros(int(seconds * SAMPLE_RATE)) + rng.normal(0, QUIET_HISS_RMS, int(seconds * SAMPLE_RATE))
            x[at : at + speech.size] += speech
            return x
        return mix(speech, noise(seconds, rng), snr, at)

    return {"snr_db": "quiet" if snr is None else snr, **run_streams(engine, clips, build, config, policy, seed)}


QUIET_HISS_RMS = 3e-4
"""A quiet room through the microphone: a faint hiss (about -70 dBFS)."""


def run_streams(engine: Engine, clips: list[Item], build: Callable[[np.ndarray, np.random.Generator], np.ndarray],
                config: SegmenterConfig, policy: Policy, seed: int) -> dict[str, object]:
    """Each clip's speech (float, ±1) made into a stream by `build` (the speech `LEAD_S` in), clipped to full scale
    as a sound card does, and fed to the segmenter and the engine (`stream`): commands heard, other words taken,
    false walks, segments, end of speech -> segment; and each word's outcome in the clips' order (`commands_heard_each`,
    `others_taken_each`: "1" heard / taken, "0" not), so that two runs on the same clips can be compared word for word
    (`paired`)."""
    rng = np.random.default_rng(seed)
    each: dict[str, list[str]] = {"commands_heard_each": [], "others_taken_each": []}
    heard = Counter()
    total = Counter()
    oov_taken = 0
    oov = 0
    lengths: list[float] = []
    latency: list[float] = []
    missed_segment = 0
    errors: Counter[str] = Counter()
    walked_on: Counter[str] = Counter()
    switched: Counter[str] = Counter()
    for it in clips:
        speech = np.frombuffer(it.pcm, "<i2") / 32768.0
        x = np.clip(build(speech, rng), -1.0, 1.0)
        word_start, word_end = LEAD_S, LEAD_S + speech.size / SAMPLE_RATE
        segs = stream(engine, x, config, switched)
        lengths += [end - start for _, start, end, _, _ in segs]
        over = [s for s in segs if s[1] < word_end and s[2] > word_start]
        if not over:
            missed_segment += 1
        got = next(((cmd, conf, emit) for emit, _, _, cmd, conf in over if cmd is not None), (None, 0.0, None))
        cmd, conf, emit = got
        if it.label < OTHER:
            word = WORDS[it.label]
            total[word] += 1
            ok = cmd is not None and cmd.value == word and policy.takes(cmd, conf) is not None
            heard[word] += ok
            each["commands_heard_each"].append("01"[ok])
            if ok and emit is not None:
                latency.append(emit - (word_start + speech_end_s(it.pcm)))
            if not ok:
                errors[f"{word}->{cmd.value if cmd else 'none'}"] += 1
        else:
            oov += 1
            taken = policy.takes(cmd, conf)
            oov_taken += taken is not None
            each["others_taken_each"].append("01"[taken is not None])
            if taken == WALK:  # the reasoner walks without asking
                walked_on[it.text] += 1
    commands = sum(total.values())
    lat = np.array(latency) * 1000 if latency else np.zeros(1)
    return {
        "vad": config.vad,
        "highpass_hz": config.highpass_hz,
        "highpass_dc_share": config.highpass_dc_share,
        "highpass_switched_on": switched["highpass_on"],  # streams whose DC offset switched the high-pass on
        "command_accuracy": round(sum(heard.values()) / max(1, commands), 3),
        "stop": f"{heard['stop']}/{total['stop']}",
        "by_command": {w: round(heard[w] / max(1, total[w]), 2) for w in WORDS},
        "oov_accepted": round(oov_taken / max(1, oov), 3),
        "false_walks": sum(walked_on.values()),
        "walked_on": dict(walked_on),
        "no_segment_over_word": missed_segment,
        "segments_per_clip": round(len(lengths) / max(1, len(clips)), 2),
        "segment_s_p50_p90_max": [round(float(np.percentile(lengths, q)), 2) for q in (50, 90, 100)] if lengths else [],
        "end_of_speech_to_segment_ms_p50_p90": [round(float(np.percentile(lat, q)), 1) for q in (50, 90)],
        "top_errors": dict(errors.most_common(6)),
        "n": {"commands": commands, "oov": oov},
        **{key: "".join(marks) for key, marks in each.items()},
    }


def paired(before: str, after: str) -> tuple[int, int]:
    """Two runs' `commands_heard_each` (or `others_taken_each`) on the same clips: the words the first run counted
    and the second did not (lost), and the reverse (gained)."""
    if len(before) != len(after):
        raise ValueError(f"not the same clips: {len(before)} and {len(after)} words")
    lost = sum(a == "1" and b == "0" for a, b in zip(before, after, strict=True))
    return lost, sum(a == "0" and b == "1" for a, b in zip(before, after, strict=True))


def speech_power(clips: list[Item]) -> float:
    """The median power of the commands' active speech (as `mix` measures it)."""
    return float(np.median([active_power(np.frombuffer(it.pcm, "<i2") / 32768.0) for it in clips]))


def noise_only(engine: Engine, seconds: float, level_rms: float, config: SegmenterConfig, policy: Policy, seed: int,
               noise: Noise, mic_rate: int | None = None, dc: float = 0.0) -> dict[str, object]:
    """The robot's noise alone at `level_rms`, no one speaking: what the robot hears in it (through a microphone
    with the DC offset `dc`)."""
    rng = np.random.default_rng(seed + 1)
    x = through_mic(noise(seconds, rng) * level_rms, mic_rate) + dc
    segs = stream(engine, x, config)
    heard = Counter(cmd.value for _, _, _, cmd, conf in segs if cmd is not None and policy.takes(cmd, conf))
    return {"vad": config.vad, "seconds": seconds, "level_rms": round(level_rms, 4), "segments": len(segs), "commands_heard": dict(heard),
            "segment_s_max": round(max((e - s for _, s, e, _, _ in segs), default=0.0), 2)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engine", default="spotter")
    ap.add_argument("--head", help="spotter head file (default: the committed default head)")
    ap.add_argument("--seed", type=int, default=1, help="voice_bench's held-out seed (its rendered clips are reused)")
    ap.add_argument("--snr", default="20,10,5,0", help="speech-to-ego-noise ratios, dB (quiet is always run)")
    ap.add_argument("--per-family", type=int, default=14, help="clean commands and as many non-commands per family")
    ap.add_argument("--noise-only", type=float, default=60.0, help="seconds of the robot's noise alone")
    ap.add_argument("--noise-only-snr", type=float, default=10.0,
                    help="its level: this far (dB) below the median command's speech")
    ap.add_argument("--standing", action="store_true",
                    help="the robot standing still (its fan and the servos' holding hiss) instead of walking")
    ap.add_argument("--noise-wav", type=Path, help="a recording of your robot walking (16 kHz mono WAV) instead of the model")
    ap.add_argument("--vad", default="webrtc,silero", help="the segmenter's VADs to compare")
    ap.add_argument("--silero-threshold", type=float, default=SegmenterConfig.threshold,
                    help="Silero's speech threshold (SegmenterConfig.threshold)")
    ap.add_argument("--silero-end-threshold", type=float, default=SegmenterConfig.end_threshold,
                    help="Silero's end threshold, at most the start threshold (default: the service's, SegmenterConfig.end_threshold)")
    ap.add_argument("--early-look", type=early_look_arg, default=SegmenterConfig.early_quiet_s,
                    help="the segmenter's early look: seconds of quiet, or off (default: the service's)")
    ap.add_argument("--clear-window", type=early_look_arg, default=SegmenterConfig.clear_quiet_s,
                    help="the end window in a clear stream: seconds of quiet, or off (default: the service's)")
    add_lift_options(ap)
    ap.add_argument("--mic-rate", type=int, help="every stream through a microphone at this rate, resampled by the "
                                                   "service (`mic.ToServiceRate`; default: 16 kHz as it is)")
    ap.add_argument("--dc", type=float, default=0.0, help="the microphone's DC offset, a fraction of full scale added "
                                                          "to every stream (0.03: -30 dBFS; voice README)")
    ap.add_argument("--noise-seed", type=int, help="seed of the robot's noise and the room's hiss (default: --seed); "
                                                   "another seed is a twin draw over the same words")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    policy = Policy.from_knowledge()
    recording = np.frombuffer(read_wav(args.noise_wav), "<i2") / 32768.0 if args.noise_wav else None
    model = EgoNoiseModel(walking=not args.standing)

    def noise(seconds: float, rng: np.random.Generator) -> np.ndarray:
        return noise_source(seconds, rng, recording, model)

    clips = pick(heldout_items(args.seed, args.workers), args.per_family, args.seed)
    noise_seed = args.seed if args.noise_seed is None else args.noise_seed
    engine = make_engine(args.engine, head_path=args.head if args.engine == "spotter" else None)
    rows: list[dict[str, object]] = []
    alone: list[dict[str, object]] = []
    level = np.sqrt(speech_power([c for c in clips if c.label < OTHER]) / 10 ** (args.noise_only_snr / 10))
    for vad in args.vad.split(","):
        config = SegmenterConfig(vad=vad, threshold=args.silero_threshold, end_threshold=args.silero_end_threshold,
                                 early_quiet_s=args.early_look,
                                 clear_quiet_s=args.clear_window, **lift_settings(args))
        for snr in [None, *(float(s) for s in args.snr.split(",") if s)]:
            row = {**run_ratio(engine, clips, snr, config, policy, noise_seed, noise, args.mic_rate, args.dc),
                   "noise_seed": noise_seed}
            rows.append(row)
            print(json.dumps(row), flush=True)
        alone.append(noise_only(engine, args.noise_only, float(level), config, policy, noise_seed, noise, args.mic_rate,
                                args.dc))
        print(json.dumps({"noise_only": alone[-1]}), flush=True)
    print()
    print(f"{'VAD':7} {'SNR dB':>6} {'cmd acc':>7} {'stop':>7} {'OOV acc':>7} {'no seg':>6} {'seg/clip':>8} {'seg s p90':>9} {'EoS->seg p50':>12}")
    for r in rows:
        print(f"{r['vad']:7} {r['snr_db']!s:>6} {r['command_accuracy']:7.3f} {r['stop']:>7} {r['oov_accepted']:7.3f} "
              f"{r['no_segment_over_word']:6d} {r['segments_per_clip']:8.2f} {r['segment_s_p50_p90_max'][1]:9.2f} "
              f"{r['end_of_speech_to_segment_ms_p50_p90'][0]:12.1f}")
    for q in alone:
        print(f"{q['vad']:7} {'standing' if args.standing else 'walking'} noise alone, {q['seconds']:.0f} s, {args.noise_only_snr:.0f} dB under the median command: "
              f"{q['segments']} segments (longest {q['segment_s_max']} s), commands heard: {q['commands_heard'] or 'none'}")
    if args.json:
        args.json.write_text(json.dumps({"ratios": rows, "noise_only": alone}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
