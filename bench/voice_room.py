"""A command said across a room: the robot's microphone 1, 2 and 4 m from the person, in a room that echoes
(prints figures; not a test).

`voice_levels.py` makes a far voice a quieter one; a room makes it a more reverberant one too. Past the room's
critical distance (under a metre in an ordinary office or classroom) the microphone hears more of the walls'
reflections than of the person, so the speech reaches it smeared over the room's reverberation time and barely
quieter than nearby. The spotter's training adds a reverberation of its own making (`training.augment`: a decaying
noise tail, RT60 0.15-0.7 s, in about a third of its clips); this bench uses another generator, pyroomacoustics'
image-source model of a shoebox room, with the room's size, its reverberation time, the robot's and the person's
places drawn for each clip:

- the room 5-10 x 3.5-7 m, 2.5-3.2 m high, its walls' absorption set by Sabine's formula for a reverberation time
  drawn from `--rt60`; an image-source shoebox rings longer than Sabine says (1.0-1.7 x here), so each row also
  gives the time measured from the responses (T30);
- the robot's microphone 0.45 m above the floor (the robot on the floor) or 1.2 m (on a table), at least 0.5 m from
  the walls; the person's mouth 1.2-1.75 m high (sitting or standing), `--distances` away across the floor in one
  direction drawn so that every distance fits in the room. Speaker and microphone are omnidirectional (a mouth
  faces the listener, which would lift the direct sound a few dB over the reflections: this room is harsher there);
- the speech scaled so that its direct sound alone would peak at `--peak` dBFS at 1 m (falling 6 dB per doubling of
  distance), placed `voice_walking.LEAD_S` into a quiet room's hiss (`--floor`), through a microphone at
  `--mic-rate` Hz, to the service's path (`Segmenter` in 30 ms chunks, then the engine: `voice_walking.run_streams`).

Each distance is measured twice on the same clips: `free` (the direct sound alone, as outdoors: only the level
falls) and `room` (direct sound and reflections); the pair says what the echo costs beyond the level. The response
is aligned on its direct sound, 2.5 ms in (the end of speech is the end of the direct sound; the reverberant tail after it is
part of the latency). Per row: the responses' direct-to-reverberant ratio and T30, commands heard right (for "go", at least the reasoner's `^min-confidence`), "stop",
other words taken for a command, false walks, words no segment covered, end of speech -> segment.

    nice -n 10 .venv/bin/python bench/voice_room.py --seed 2281 --mic-rate 48000
    .venv/bin/python bench/voice_room.py --per-family 4 --distances 1,4 --json out.json
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import fftconvolve

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import Policy, add_lift_options, heldout_items, lift_settings, through_mic  # noqa: E402
from bench.voice_levels import at_level, in_room  # noqa: E402
from bench.voice_walking import pick, run_streams  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402

ROOM_SIZE_M = ((5.0, 10.0), (3.5, 7.0), (2.5, 3.2))
"""Length, width and height ranges of the room."""
MIC_HEIGHTS_M = (0.45, 1.2)
"""The robot's microphone: the robot on the floor, or on a table."""
MOUTH_HEIGHT_M = (1.2, 1.75)
WALL_GAP_M = 0.5
"""Nobody and no robot closer than this to a wall."""
SPEED_OF_SOUND = 343.0
DIRECT_AT = 40
"""Where a response's direct sound is (samples, 2.5 ms): pyroomacoustics' fractional-delay filter rings this long
before and after it."""


@dataclass(frozen=True)
class Room:
    """One clip's room and places: where the robot's microphone is, and the person's mouth at each distance."""

    size: tuple[float, float, float]
    rt60: float
    mic: tuple[float, float, float]
    mouths: tuple[tuple[float, float, float], ...]

    def distances(self) -> list[float]:
        """From each mouth to the microphone, through the air (m)."""
        return [float(np.linalg.norm(np.subtract(mouth, self.mic))) for mouth in self.mouths]


def rt60_range(raw: str) -> tuple[float, float]:
    """`--rt60`: two reverberation times in seconds, low then high; ValueError otherwise."""
    try:
        low, high = (float(t) for t in raw.split(","))
    except ValueError:
        low = high = -1.0
    if not 0.05 <= low <= high:
        raise ValueError(f"--rt60: two times in seconds, low then high (got {raw!r})")
    return low, high


def draw_room(rng: np.random.Generator, distances: list[float], rt60: tuple[float, float]) -> Room:
    """A room, the robot's place in it, and a direction from the robot along which the person stands at every one of
    `distances` (horizontal, metres) at least `WALL_GAP_M` from the walls; redrawn until all fit."""
    for _ in range(1000):
        size = tuple(float(rng.uniform(*r)) for r in ROOM_SIZE_M)
        robot = np.array([rng.uniform(WALL_GAP_M, size[0] - WALL_GAP_M), rng.uniform(WALL_GAP_M, size[1] - WALL_GAP_M)])
        angle = rng.uniform(0.0, 2 * np.pi)
        way = np.array([np.cos(angle), np.sin(angle)])
        feet = [robot + d * way for d in distances]
        if all(WALL_GAP_M <= p[0] <= size[0] - WALL_GAP_M and WALL_GAP_M <= p[1] <= size[1] - WALL_GAP_M for p in feet):
            mic_h = float(MIC_HEIGHTS_M[int(rng.integers(len(MIC_HEIGHTS_M)))])
            mouth_h = float(rng.uniform(*MOUTH_HEIGHT_M))
            return Room(size, float(rng.uniform(*rt60)), (float(robot[0]), float(robot[1]), mic_h),
                        tuple((float(p[0]), float(p[1]), mouth_h) for p in feet))
    raise ValueError(f"no room of {ROOM_SIZE_M} m fits a person {max(distances)} m from the robot")


def responses(room: Room) -> list[np.ndarray]:
    """The room's impulse response from the person's mouth at each distance to the robot's microphone (16 kHz;
    pyroomacoustics' image-source model, omnidirectional, computed from the microphone as source: the response is
    the same either way), each aligned so that its direct sound is at sample `DIRECT_AT` with gain 1/distance (1 at
    1 m)."""
    import pyroomacoustics as pra  # a bench dependency (the test extra), not the service's

    absorption, max_order = pra.inverse_sabine(room.rt60, list(room.size))
    shoebox = pra.ShoeBox(list(room.size), fs=SAMPLE_RATE, materials=pra.Material(absorption), max_order=max_order)
    shoebox.add_source(list(room.mic))
    shoebox.add_microphone_array(np.array(room.mouths).T)
    shoebox.compute_rir()
    delay = pra.constants.get("frac_delay_length") // 2  # the fractional-delay filter's own delay, samples
    out = []
    for k, distance in enumerate(room.distances()):
        direct = int(round(distance / SPEED_OF_SOUND * SAMPLE_RATE)) + delay
        out.append(np.asarray(shoebox.rir[k][0][direct - DIRECT_AT :], dtype=np.float64))
    return out


def free_field(room: Room) -> list[np.ndarray]:
    """The direct sound alone at each distance (as outdoors): a gain of 1/distance, at sample `DIRECT_AT`."""
    out = []
    for distance in room.distances():
        h = np.zeros(DIRECT_AT + 1)
        h[DIRECT_AT] = 1.0 / distance
        out.append(h)
    return out


class Speaker:
    """`run_streams`' `build` for one distance: each clip in turn through its room's response, at the level, in the
    quiet room's hiss, through the microphone. The responses are the clips' in `run_streams`' order."""

    def __init__(self, impulses: list[np.ndarray], peak_db: float, floor_db: float, mic_rate: int | None) -> None:
        self.impulses, self.peak_db, self.floor_db, self.mic_rate = iter(impulses), peak_db, floor_db, mic_rate

    def __call__(self, speech: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        heard = fftconvolve(at_level(speech, self.peak_db), next(self.impulses))
        return through_mic(np.clip(in_room(heard, self.floor_db, rng), -1.0, 1.0), self.mic_rate)


def direct_to_reverberant_db(h: np.ndarray) -> float:
    """The response's direct sound (its fractional-delay filter's ringing before it, and 0.5 ms after it: the first
    reflection, off the floor, comes 1-3 ms later) over the rest, in energy (dB)."""
    split = DIRECT_AT + int(0.0005 * SAMPLE_RATE) + 1
    return float(10 * np.log10(np.sum(h[:split] ** 2) / max(np.sum(h[split:] ** 2), 1e-20)))


def ringing_s(h: np.ndarray) -> float:
    """The response's reverberation time (T30 from its Schroeder decay, pyroomacoustics' `measure_rt60`), s."""
    import pyroomacoustics as pra

    return float(pra.experimental.measure_rt60(h, fs=SAMPLE_RATE, decay_db=30))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--engine", default="spotter")
    ap.add_argument("--seed", type=int, default=1, help="voice_bench's held-out seed (its rendered clips are reused)")
    ap.add_argument("--room-seed", type=int, help="seed of the rooms and places (default: --seed)")
    ap.add_argument("--distances", default="1,2,4", help="the person's distance from the robot across the floor, m")
    ap.add_argument("--rt60", default="0.25,0.6", help="the room's reverberation time is drawn from this range, s")
    ap.add_argument("--peak", type=float, default=-26.0, help="the direct sound's peak at 1 m, dBFS")
    ap.add_argument("--floor", type=float, default=-70.0, help="the room's hiss through the microphone, dBFS RMS")
    ap.add_argument("--per-family", type=int, default=14, help="clean commands and as many other words per family")
    ap.add_argument("--kinds", default="free,room", help="free (the direct sound alone), room (with its reflections)")
    ap.add_argument("--mic-rate", type=int, help="through a microphone at this rate, resampled by the service")
    add_lift_options(ap)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    distances = [float(d) for d in args.distances.split(",") if d]
    try:
        rt60 = rt60_range(args.rt60)
    except ValueError as exc:
        ap.error(str(exc))
    policy = Policy.from_knowledge()
    clips = pick(heldout_items(args.seed, args.workers), args.per_family, args.seed)
    engine = make_engine(args.engine)
    config = SegmenterConfig(**lift_settings(args))
    room_rng = np.random.default_rng(args.seed if args.room_seed is None else args.room_seed)
    rooms = [draw_room(room_rng, distances, rt60) for _ in clips]
    kinds = [k for k in args.kinds.split(",") if k]
    if unknown := set(kinds) - {"free", "room"}:
        ap.error(f"--kinds: unknown {sorted(unknown)} (free, room)")
    impulses = {"free": [free_field(r) for r in rooms]}
    if "room" in kinds:
        impulses["room"] = [responses(r) for r in rooms]
    rows: list[dict[str, object]] = []
    for k, distance in enumerate(distances):
        for kind in kinds:
            hs = [each[k] for each in impulses[kind]]
            speaker = Speaker(hs, args.peak, args.floor, args.mic_rate)
            row = run_streams(engine, clips, speaker, config, policy, args.seed)
            drr = [direct_to_reverberant_db(h) for h in hs] if kind == "room" else []
            t30 = [ringing_s(h) for h in hs] if kind == "room" else []
            rows.append({"kind": kind, "distance_m": distance, "peak_1m_dbfs": args.peak, "rt60_s": list(rt60),
                         "direct_to_reverberant_db_p10_p50_p90":
                             [round(float(np.percentile(drr, q)), 1) for q in (10, 50, 90)] if drr else None,
                         "t30_s_p10_p50_p90": [round(float(np.percentile(t30, q)), 2) for q in (10, 50, 90)] if t30 else None,
                         "mic_rate": args.mic_rate, **lift_settings(args), **row})
            print(json.dumps(rows[-1]), flush=True)
    print()
    print(f"{'distance':>8} {'kind':5} {'DRR p50':>7} {'T30 p50':>7} {'cmd acc':>7} {'stop':>7} {'OOV acc':>7} {'false walks':>11} "
          f"{'no seg':>6} {'EoS->seg p50':>12}")
    for r in rows:
        drr = r["direct_to_reverberant_db_p10_p50_p90"]
        t30 = r["t30_s_p10_p50_p90"]
        print(f"{r['distance_m']:7.1f}m {r['kind']:5} {drr[1] if drr else '-'!s:>7} {t30[1] if t30 else '-'!s:>7} "
              f"{r['command_accuracy']:7.3f} "
              f"{r['stop']:>7} {r['oov_accepted']:7.3f} {r['false_walks']:11d} {r['no_segment_over_word']!s:>6} "
              f"{r['end_of_speech_to_segment_ms_p50_p90'][0]:10.0f}ms")
    print(f"(direct sound {args.peak:.0f} dBFS peak at 1 m, RT60 {rt60[0]:g}-{rt60[1]:g} s, room hiss {args.floor:.0f} "
          f"dBFS RMS, microphone {args.mic_rate or 16000} Hz; {rows[0]['n']['commands'] if rows else 0} commands and "
          f"{rows[0]['n']['oov'] if rows else 0} other words per row; held-out seed {args.seed}, rooms seed "
          f"{args.seed if args.room_seed is None else args.room_seed})")
    if args.json:
        args.json.write_text(json.dumps({"seed": args.seed, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
