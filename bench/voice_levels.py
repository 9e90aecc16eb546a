"""How loud the speech reaches the microphone: a person far away or a gain set low, and one shouting into a
microphone that clips (prints figures; not a test).

Every clip the spotter was trained on, and every clip `voice_bench.py` measures, has its peak between about -26 and
-2 dBFS (`training.augment.Augment.draw` draws the peak from that range; the held-out clips are rendered the same
way). A real microphone gives what the room and its gain give: a person three metres from the robot, or a USB
microphone at its default gain, can peak at -40 dBFS; a person leaning in to shout "stop" drives it past full
scale, where the sound card clips. This bench says what the robot hears then.

The held-out clips (`voice_bench`'s held-out split, clean renderings, the same seed's cache, up to `--per-family`
commands and as many other words per voice family) are scaled so that the speech's peak is at each level
(`--peaks`, dBFS), or driven `--overdrive` dB past full scale and clipped there, as a sound card does. Each is
placed `LEAD_S` into a quiet room's faint hiss (`--floor`, dBFS RMS: the microphone's own noise, the same at every
level, so a quieter voice is also a noisier one) and fed to the service's path in two ways:

- `stream`: the live microphone's path, `Segmenter` (the service's VAD) in 30 ms chunks, then the engine
  (`voice_walking.run_streams`);
- `file`: the clip alone, scaled, with the same hiss, straight to the engine (what `voice_bench` measures): set
  beside `stream`, it says whether a loss is the VAD's (no segment) or the recogniser's.

`--dc` adds a microphone's DC offset to both paths (the stream's high-pass, `--highpass`, takes it out; the file
path has none, as the service's files have none).

Per level: commands heard right (for "go", at least the reasoner's `^min-confidence`), "stop", other words taken
for a command, false walks, and for `stream` how many words no segment covered.

    nice -n 10 .venv/bin/python bench/voice_levels.py --seed 3307
    .venv/bin/python bench/voice_levels.py --peaks -45,-20 --overdrive 12 --per-family 6 --json out.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import (  # noqa: E402,F401
    OTHER,
    WALK,
    WORDS,
    Item,
    Policy,
    add_lift_options,
    heldout_items,
    lift_settings,
    through_mic,
)
from bench.voice_walking import LEAD_S, TAIL_S, pick, run_streams  # noqa: E402
from services.voice.audio import SAMPLE_RATE, rounded_pcm  # noqa: E402
from services.voice.engine import Engine, make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def at_level(speech: np.ndarray, peak_db: float) -> np.ndarray:
    """`speech` scaled so that its peak is `peak_db` dBFS (above 0: driven past full scale; the caller clips)."""
    return speech * (10 ** (peak_db / 20) / (np.max(np.abs(speech)) + 1e-12))


def in_room(speech: np.ndarray, floor_db: float, rng: np.random.Generator) -> np.ndarray:
    """`speech` `LEAD_S` into the room's hiss at `floor_db` dBFS RMS, `TAIL_S` of it after."""
    at = int(LEAD_S * SAMPLE_RATE)
    n = at + speech.size + int(TAIL_S * SAMPLE_RATE)
    x = rng.normal(0.0, 10 ** (floor_db / 20), n)
    x[at : at + speech.size] += speech
    return x


def run_files(engine: Engine, clips: list[Item], peak_db: float, floor_db: float, gain_db: float, policy: Policy,
              seed: int, mic_rate: int | None = None, dc: float = 0.0) -> dict[str, object]:
    """The clip alone at the level, with 0.2 s of the room's hiss either side, through the gain (and a microphone at
    `mic_rate`: `through_mic`, with its DC offset `dc`), straight to the engine."""
    rng = np.random.default_rng(seed)
    heard: Counter[str] = Counter()
    total: Counter[str] = Counter()
    oov = oov_taken = walks = 0
    errors: Counter[str] = Counter()
    pad = int(0.2 * SAMPLE_RATE)
    for it in clips:
        speech = at_level(np.frombuffer(it.pcm, "<i2") / 32768.0, peak_db)
        x = rng.normal(0.0, 10 ** (floor_db / 20), speech.size + 2 * pad)
        x[pad : pad + speech.size] += speech
        rec = engine.recognise(rounded_pcm(through_mic(np.clip(x, -1.0, 1.0) * 10 ** (gain_db / 20), mic_rate) + dc))
        taken = policy.takes(rec.command, rec.confidence)
        if it.label < OTHER:
            word = WORDS[it.label]
            total[word] += 1
            ok = rec.command is not None and rec.command.value == word and taken is not None
            heard[word] += ok
            if not ok:
                errors[f"{word}->{rec.command.value if rec.command else 'none'}"] += 1
        else:
            oov += 1
            oov_taken += taken is not None
            walks += taken == WALK
    commands = sum(total.values())
    return {"command_accuracy": round(sum(heard.values()) / max(1, commands), 3), "stop": f"{heard['stop']}/{total['stop']}",
            "by_command": {w: round(heard[w] / max(1, total[w]), 2) for w in WORDS},
            "oov_accepted": round(oov_taken / max(1, oov), 3), "false_walks": walks,
            "top_errors": dict(errors.most_common(6)), "n": {"commands": commands, "oov": oov}}


def levels(peaks: str, overdrive: str) -> list[float]:
    """The speech's peak levels, dBFS: `peaks`, then `overdrive`'s dB past full scale."""
    return [float(p) for p in peaks.split(",") if p] + [float(d) for d in overdrive.split(",") if d]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engine", default="spotter")
    ap.add_argument("--head", help="spotter head file (default: the committed default head)")
    ap.add_argument("--seed", type=int, default=1, help="voice_bench's held-out seed (its rendered clips are reused)")
    ap.add_argument("--peaks", default="-50,-44,-38,-32,-26,-14,-3", help="the speech's peak, dBFS")
    ap.add_argument("--overdrive", default="6,12,20", help="dB past full scale, clipped there")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss through the microphone, dBFS RMS")
    ap.add_argument("--gain", type=float, default=0.0,
                    help="dB of gain on what the sound card gave (clipped there), speech and hiss alike (HRI_VOICE_GAIN)")
    ap.add_argument("--per-family", type=int, default=14, help="clean commands and as many other words per family")
    ap.add_argument("--paths", default="stream,file", help="stream (VAD, then the engine), file (the engine alone)")
    add_lift_options(ap)
    ap.add_argument("--mic-rate", type=int, help="both paths through a microphone at this rate, resampled by the "
                                                   "service (`mic.ToServiceRate`; default: 16 kHz as it is)")
    ap.add_argument("--dc", type=float, default=0.0, help="the microphone's DC offset, a fraction of full scale added "
                                                          "to what it hands over (0.03: -30 dBFS; voice README)")
    ap.add_argument("--hiss-seed", type=int, help="seed of the room's hiss (default: --seed); another seed is a twin "
                    "run, the same words in another draw of the same hiss, which shows how much a row moves by chance")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    policy = Policy.from_knowledge()
    clips = pick(heldout_items(args.seed, args.workers), args.per_family, args.seed)
    engine = make_engine(args.engine, head_path=args.head if args.engine == "spotter" else None)
    config = SegmenterConfig(**lift_settings(args))
    hiss_seed = args.seed if args.hiss_seed is None else args.hiss_seed
    rows: list[dict[str, object]] = []
    for peak in levels(args.peaks, args.overdrive):
        for path in args.paths.split(","):
            if path == "stream":
                def build(speech: np.ndarray, rng: np.random.Generator, peak: float = peak) -> np.ndarray:
                    x = np.clip(in_room(at_level(speech, peak), args.floor, rng), -1.0, 1.0) * 10 ** (args.gain / 20)
                    return through_mic(x, args.mic_rate) + args.dc

                row = run_streams(engine, clips, build, config, policy, hiss_seed)
            elif path == "file":
                row = run_files(engine, clips, peak, args.floor, args.gain, policy, hiss_seed, args.mic_rate, args.dc)
            else:
                ap.error(f"--paths: unknown path {path!r} (stream, file)")
            rows.append({"path": path, "peak_dbfs": peak, "gain_db": args.gain, "hiss_seed": hiss_seed, **lift_settings(args),
                         "mic_rate": args.mic_rate, "dc": args.dc, **row})
            print(json.dumps(rows[-1]), flush=True)
    print()
    print(f"speech peak -> {'path':6} {'cmd acc':>7} {'stop':>7} {'OOV acc':>7} {'false walks':>11} {'no seg':>6} "
          f"{'HP on':>5}")
    for r in rows:
        label = f"{r['peak_dbfs']:+.0f} dBFS" + (" (clipped)" if r["peak_dbfs"] > 0 else "")
        print(f"{label:14} {r['path']:6} {r['command_accuracy']:7.3f} {r['stop']:>7} {r['oov_accepted']:7.3f} "
              f"{r['false_walks']:11d} {r.get('no_segment_over_word', '-')!s:>6} "
              f"{r.get('highpass_switched_on', '-')!s:>5}")
    print(f"(room hiss {args.floor:.0f} dBFS RMS, gain {args.gain:+.0f} dB, VAD lift {args.vad_lift or 'off'}, DC offset "
          f"{args.dc:g}, high-pass {args.highpass or 'off'} (HP on: streams it was switched on in); "
          f"{rows[0]['n']['commands'] if rows else 0} commands and "
          f"{rows[0]['n']['oov'] if rows else 0} other words per row; held-out seed {args.seed}, hiss seed {hiss_seed})")
    if args.json:
        args.json.write_text(json.dumps({"floor_dbfs": args.floor, "gain_db": args.gain, "seed": args.seed, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
