"""What a walking OP2's own microphones hear: a model of the robot's ego-noise, driven by the gait the
motion service runs.

No recording of an OP2 walking is available here, so this is a physical *model*, with its assumptions
stated, not a recording. It is used only to measure (`bench/voice_walking.py`); nothing is trained on it.

- **Servo whine.** Each of the 20 joints is an MX-28: a coreless DC motor behind a 193:1 metal gear train.
  A joint turning at v deg/s spins its motor at f = v * 193 / 360 Hz, and the gear train sings at its
  mesh orders (`MESH_ORDERS` x f: a pinion of 10 and 14 teeth) with weaker motor orders (1-3 x f).
  The joint speeds come from `services.motion.gait.Gait`, tick by tick, so the whine sweeps up and down
  with every step (0 to about 1.5 kHz at the default gait), as a walking humanoid's does. Loudness grows
  with speed (`speed_exponent`); each motor's pitch wanders a little (`jitter`).
- **Footfalls.** At each foot's landing (the gait's double support begins): a thump (noise decaying in
  about 15 ms, below 600 Hz) and a click (2 ms, 2-6 kHz), each ±3 dB from step to step.
- **Backlash ticks.** A joint whose turning reverses takes up its gear backlash: a 1 ms tick.
- **Holding hiss and fan.** Servos holding load under PWM, and the cooling fan of the robot's PC:
  broadband noise (pink, 100 Hz - 7 kHz) and the fan's blade-pass hum, present walking or standing.

`ego_noise(seconds, rng)` gives the sum at unit RMS; callers scale it to the speech-to-noise ratio they
study. The component levels (`EgoNoiseModel`) are guesses in the right order (the whine dominates while
walking); a user with a recording of their own robot should measure with it instead (`--noise-wav`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfilt

from services.motion.gait import Gait, GaitParams
from services.motion.joints import TICKS_PER_DEGREE
from services.voice.audio import SAMPLE_RATE
from services.voice.synth import noise
from services.voice.training.augment import active_power

GEAR_RATIO = 193.0
"""MX-28 reduction."""
MESH_ORDERS = ((10, 1.0), (14, 0.6), (1, 0.25), (2, 0.2), (3, 0.15))
"""(multiple of the motor's rotation rate, relative amplitude)."""


@dataclass(frozen=True)
class EgoNoiseModel:
    walking: bool = True
    """False: the robot stands still (fan and holding hiss only)."""
    whine: float = 1.0
    footfall: float = 0.8
    backlash: float = 0.15
    hiss: float = 0.08
    fan_hum: float = 0.04
    speed_exponent: float = 0.7
    jitter: float = 0.02
    """Relative wander of each motor's pitch."""
    fan_hz: float = 140.0


def joint_speeds(seconds: float, params: GaitParams | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The gait's joint speeds, deg/s, one row per control tick (ticks, joints), and the tick times (s) at
    which a foot lands."""
    gait = Gait(params or GaitParams())
    dt = gait.params.dt
    poses, landings, was_double = [], [], True
    for k in range(int(np.ceil(seconds / dt)) + 2):
        frame = gait.next()
        if frame is None:  # never while no stop is requested
            break
        if frame.double_support and not was_double:
            landings.append(k * dt)
        was_double = frame.double_support
        poses.append([frame.pose[j] for j in sorted(frame.pose)])
    deg = np.asarray(poses, dtype=np.float64) / TICKS_PER_DEGREE
    return np.abs(np.gradient(deg, dt, axis=0)), np.asarray(landings)


def _burst(n: int, tau_s: float, band: tuple[float, float] | None, rng: np.random.Generator) -> np.ndarray:
    t = np.arange(n) / SAMPLE_RATE
    x = rng.normal(size=n) * np.exp(-t / tau_s)
    if band is not None:
        lo, hi = band
        kind = "lowpass" if lo <= 0 else "bandpass"
        wn = hi if lo <= 0 else [lo, hi]
        x = sosfilt(butter(2, wn, btype=kind, fs=SAMPLE_RATE, output="sos"), x)
    return x / (np.max(np.abs(x)) + 1e-12)


def _add(out: np.ndarray, at: int, x: np.ndarray) -> None:
    if 0 <= at < out.size:
        seg = x[: out.size - at]
        out[at : at + seg.size] += seg


def unit_rms(x: np.ndarray) -> np.ndarray:
    return x / (np.sqrt(np.mean(x**2)) + 1e-12)


def ego_noise(seconds: float, rng: np.random.Generator, model: EgoNoiseModel | None = None,
              params: GaitParams | None = None) -> np.ndarray:
    """`seconds` of the robot's own noise at 16 kHz, unit RMS (float64). The gait starts at a random phase."""
    m = model or EgoNoiseModel()
    n = int(seconds * SAMPLE_RATE)
    t = np.arange(n) / SAMPLE_RATE
    out = np.zeros(n)
    hiss = sosfilt(butter(2, [100.0, 7000.0], btype="bandpass", fs=SAMPLE_RATE, output="sos"), noise("pink", n, rng))
    out += m.hiss * unit_rms(hiss)
    fan = np.sin(2 * np.pi * m.fan_hz * t + rng.uniform(0, 2 * np.pi))
    out += m.fan_hum * np.sqrt(2) * (fan + 0.3 * np.sin(4 * np.pi * m.fan_hz * t))
    if m.walking:
        p = params or GaitParams()
        offset = float(rng.uniform(0, p.period))
        speeds, landings = joint_speeds(seconds + offset + p.period, p)
        ticks = np.arange(len(speeds)) * p.dt - offset
        top = float(np.percentile(speeds.max(axis=1), 95)) or 1.0
        whine = np.zeros(n)
        for j in range(speeds.shape[1]):
            v = np.interp(t, ticks, speeds[:, j])
            if v.max() < 1.0:  # a joint the gait holds still (the head, the elbows)
                continue
            motor_hz = v * GEAR_RATIO / 360.0
            wander = 1.0 + m.jitter * np.cumsum(rng.normal(size=n)) / np.sqrt(SAMPLE_RATE)
            phase = 2 * np.pi * np.cumsum(motor_hz * wander) / SAMPLE_RATE
            level = (v / top) ** m.speed_exponent
            for order, amp in MESH_ORDERS:
                audible = order * motor_hz < 0.45 * SAMPLE_RATE
                whine += audible * amp * level * np.sin(order * phase + rng.uniform(0, 2 * np.pi))
            reversals = np.flatnonzero(np.diff(np.sign(np.gradient(v[::160]))) > 0)
            for r in reversals:  # speed passes a minimum: the joint turns round and takes up its backlash
                if v[r * 160] < 5.0:
                    _add(out, r * 160, m.backlash * _burst(16, 0.001, (1500.0, 6000.0), rng))
        out += m.whine * unit_rms(whine)
        for land in landings - offset:
            at = int(land * SAMPLE_RATE)
            gain = 10 ** (rng.uniform(-3, 3) / 20)
            _add(out, at, m.footfall * gain * _burst(int(0.08 * SAMPLE_RATE), 0.015, (0.0, 600.0), rng))
            _add(out, at, 0.5 * m.footfall * gain * _burst(int(0.01 * SAMPLE_RATE), 0.002, (2000.0, 6000.0), rng))
    return unit_rms(out)


def mix(speech: np.ndarray, ego: np.ndarray, snr_db: float, at: int) -> np.ndarray:
    """`ego` (unit RMS) scaled so that the speech's active part is `snr_db` above it, with `speech` (float,
    ±1 full scale) added from sample `at`."""
    out = ego * np.sqrt(active_power(speech) / 10 ** (snr_db / 10))
    out[at : at + speech.size] += speech[: out.size - at]
    return out
