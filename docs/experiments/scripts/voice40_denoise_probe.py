"""Round voice40, tuning data only: is a segment heard better with the noise before it subtracted?

Round 15 found the spotter itself failing in a walking robot's noise at 10 dB (an oracle segmenter: 0.31 of commands)
and RNNoise in front of it helping at 10 dB, hurting at 20 dB (scratch). Here a stationary spectral gate
(`noisereduce`, its noise profile the stream's last second before the segment) is tried on tuning clips only, in a
machine noise made unlike the bench's OP2 model (round 15b's `machine_noise`: random motors, impacts, hiss; the walking
bench's `ego_noise` stays held out), and in pink noise. Each segment over the word is decoded as it came and denoised
(several strengths); its `snr_db` is kept, so a gate on the segmenter's own estimate can be read afterwards.

    .venv/bin/pip install noisereduce   # not a dependency of the project: this probe's alone
    .venv/bin/python docs/experiments/scripts/voice40_denoise_probe.py --json /tmp/s80/probe.json

Stop 80 ran the machine noise's three rows (docs/experiments/voice-rounds.md, "Round voice40"); pink was not run.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import noisereduce
import numpy as np
from scipy.signal import butter, sosfilt

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402

from bench.ego_noise import mix  # noqa: E402
from bench.voice_bench import OTHER, WORDS, Policy  # noqa: E402
from bench.voice_walking import CHUNK, LEAD_S, TAIL_S  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402
from services.voice.training.augment import noise  # noqa: E402

STRENGTHS = (0.5, 0.75, 1.0)


def machine_noise(n: int, rng: np.random.Generator) -> np.ndarray:
    """Round 15b's tuning-side machine (docs/experiments/scripts/voice15_machine_noise.patch), unit RMS."""
    t = np.arange(n) / SAMPLE_RATE
    out = np.zeros(n)
    for _ in range(int(rng.integers(1, 5))):
        base, depth = rng.uniform(20.0, 200.0), rng.uniform(0.0, 1.0)
        motion = np.abs(np.sin(np.pi * t / rng.uniform(0.25, 1.5) + rng.uniform(0.0, np.pi)))
        f0 = base * (1.0 - depth + depth * motion)
        phase = 2 * np.pi * np.cumsum(f0) / SAMPLE_RATE
        tilt = rng.uniform(0.3, 1.5)
        motor = np.zeros(n)
        for order in rng.choice(np.arange(1, 25), size=int(rng.integers(3, 9)), replace=False):
            motor += (order * f0 < 0.49 * SAMPLE_RATE) * order**-tilt * np.sin(order * phase + rng.uniform(0, 2 * np.pi))
        out += rng.uniform(0.3, 1.0) * (1.0 - depth + depth * motion) * motor / (np.sqrt(np.mean(motor**2)) + 1e-12)
    if rng.random() < 0.7:
        period, decay = rng.uniform(0.2, 1.0), rng.uniform(0.002, 0.04)
        m = int(5 * decay * SAMPLE_RATE)
        tone = butter(2, rng.uniform(300.0, 4000.0), btype="lowpass", fs=SAMPLE_RATE, output="sos")
        level = rng.uniform(0.5, 3.0)
        for at in np.arange(rng.uniform(0.0, period), n / SAMPLE_RATE, period):
            at_i = int((at + rng.normal(0.0, 0.01)) * SAMPLE_RATE)
            if 0 <= at_i < n:
                burst = sosfilt(tone, rng.normal(size=m) * np.exp(-np.arange(m) / (decay * SAMPLE_RATE)))
                seg = burst[: n - at_i]
                out[at_i : at_i + seg.size] += level * rng.uniform(0.5, 1.5) * seg / (np.max(np.abs(burst)) + 1e-12)
    out += rng.uniform(0.02, 0.3) * noise("pink", n, rng)
    return out / (np.sqrt(np.mean(out**2)) + 1e-12)


def denoise(pcm: bytes, profile: np.ndarray, strength: float) -> bytes:
    x = np.frombuffer(pcm, "<i2").astype(np.float32) / 32768.0
    y = noisereduce.reduce_noise(y=x, sr=SAMPLE_RATE, y_noise=profile, stationary=True, prop_decrease=strength,
                                 n_fft=512, win_length=512, hop_length=128)
    return (np.clip(y, -1, 1) * 32767).astype("<i2").tobytes()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--snrs", default="20,10,5")
    ap.add_argument("--noises", default="machine", help="machine and/or pink, comma-separated")
    ap.add_argument("--seed", type=int, default=40)
    ap.add_argument("--json", type=Path, required=True)
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine = make_engine("spotter")
    policy = Policy.from_knowledge()
    rows = []
    for kind in args.noises.split(","):
        for snr in (float(v) for v in args.snrs.split(",")):
            rng = np.random.default_rng(args.seed)
            for it in items:
                speech = np.frombuffer(it.pcm, "<i2") / 32768.0
                n = int((LEAD_S + TAIL_S) * SAMPLE_RATE) + speech.size
                bg = machine_noise(n, rng) if kind == "machine" else noise(kind, n, rng)
                bg = bg / (np.sqrt(np.mean(bg**2)) + 1e-12)
                x = np.clip(mix(speech, bg, snr, int(LEAD_S * SAMPLE_RATE)), -1, 1)
                pcm = (x * 32767).astype("<i2").tobytes()
                seg = Segmenter(SegmenterConfig())
                segs = []
                for k in range(0, len(pcm), CHUNK):
                    segs += seg.feed(pcm[k : k + CHUNK])
                segs += seg.flush()
                w0, w1 = LEAD_S, LEAD_S + speech.size / SAMPLE_RATE
                out = []
                for s in segs:
                    if not (s.start_s < w1 and s.end_s > w0):
                        continue
                    a = int(s.start_s * SAMPLE_RATE)
                    profile = x[max(0, a - SAMPLE_RATE) : max(0, a - int(0.05 * SAMPLE_RATE))].astype(np.float32)
                    rec = {"raw": engine.recognise(s.pcm)}
                    if profile.size >= SAMPLE_RATE // 4:
                        for st in STRENGTHS:
                            rec[str(st)] = engine.recognise(denoise(s.pcm, profile, st))
                    out.append({"snr_db": s.snr_db, "len_s": round(s.end_s - s.start_s, 2),
                                **{k: [r.command.value if r.command else None, round(r.confidence, 3),
                                       policy.takes(r.command, r.confidence)] for k, r in rec.items()}})
                rows.append({"noise": kind, "snr": snr, "label": int(it.label), "text": it.text, "segs": out})
            sub = [r for r in rows if r["noise"] == kind and r["snr"] == snr]
            summary = {}
            for v in ("raw", *map(str, STRENGTHS)):
                ok = oov = 0
                for r in sub:
                    got = next(((s[v][0], s[v][2]) for s in r["segs"] if v in s and s[v][0] is not None), (None, None))
                    if r["label"] < OTHER:
                        ok += got[0] == WORDS[r["label"]] and got[1] is not None
                    else:
                        oov += got[1] is not None
                nc = sum(r["label"] < OTHER for r in sub)
                summary[v] = f"{ok / nc:.3f} / {100 * oov / (len(sub) - nc):.1f} %"
            print(kind, snr, json.dumps(summary), flush=True)
    args.json.write_text(json.dumps(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
