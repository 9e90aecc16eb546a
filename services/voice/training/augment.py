"""Audio augmentation for training clips: tempo, gain, room reverberation, a robot microphone's band
limits, and noise at a chosen SNR. Every random choice comes from the caller's generator."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.signal import butter, fftconvolve, resample_poly, sosfilt

from services.voice.audio import SAMPLE_RATE
from services.voice.synth import noise

NOISE_KINDS = ("white", "pink", "brown", "hum", "babble")


@dataclass(frozen=True)
class Augment:
    tempo: float = 1.0
    """Playback-rate factor (resampling: changes pitch with speed)."""
    reverb_rt60: float = 0.0
    band: tuple[float, float] | None = None
    """High-pass and low-pass corner frequencies (Hz)."""
    noise: str | None = None
    snr_db: float = 30.0
    peak: float = 0.5
    pad_s: tuple[float, float] = (0.4, 0.4)
    floor_dbfs: float | None = None
    """A microphone's own hiss under everything, dBFS RMS (white, low-passed at 7.2 kHz as a converter's
    anti-alias filter leaves it: voice README, stop 71); None: only the 16-bit dither."""

    @classmethod
    def draw(cls, rng: np.random.Generator, strength: float = 1.0) -> Augment:
        """A random augmentation; `strength` 0 gives the clean clip (only padding and gain vary)."""
        tempo = float(rng.uniform(0.88, 1.12)) if rng.random() < 0.5 * strength else 1.0
        rt60 = float(rng.uniform(0.15, 0.7)) if rng.random() < 0.35 * strength else 0.0
        band = (float(rng.uniform(80, 400)), float(rng.uniform(3000, 7000))) if rng.random() < 0.3 * strength else None
        kind = str(rng.choice(NOISE_KINDS)) if rng.random() < 0.7 * strength else None
        return cls(tempo=tempo, reverb_rt60=rt60, band=band, noise=kind, snr_db=float(rng.uniform(3, 30)),
                   peak=float(10 ** rng.uniform(-1.3, -0.1)), pad_s=(float(rng.uniform(0.2, 0.7)),
                                                                    float(rng.uniform(0.2, 0.7))))


FAR_PEAK_DBFS = (-48.0, -26.0)
"""`far`: the peak of a far or quiet voice, dBFS (the default draw's peaks are -26 to -2)."""
FAR_FLOOR_DBFS = (-74.0, -66.0)
"""`far`: the microphone's hiss under it, dBFS RMS (the levels bench's quiet room is -70)."""


def far(aug: Augment, rng: np.random.Generator, share: float) -> Augment:
    """`aug`, or with probability `share` the same clip said from further away: its peak drawn from `FAR_PEAK_DBFS`,
    over a microphone's hiss from `FAR_FLOOR_DBFS` (round voice39). A far voice is a noisier one: at -44 dBFS peak
    over -70 dBFS of hiss the speech is about 13 dB above it. Draws from `rng` only, so the clip's other choices
    are the ones `Augment.draw` made."""
    if not rng.random() < share:
        return aug
    return replace(aug, peak=float(10 ** (rng.uniform(*FAR_PEAK_DBFS) / 20)),
                   floor_dbfs=float(rng.uniform(*FAR_FLOOR_DBFS)))


def hiss(n: int, rms_dbfs: float, rng: np.random.Generator) -> np.ndarray:
    """A microphone's own noise: white, low-passed at 7.2 kHz, at `rms_dbfs` RMS."""
    x = sosfilt(butter(4, 7200.0, btype="lowpass", fs=SAMPLE_RATE, output="sos"), rng.normal(size=n))
    return x * 10 ** (rms_dbfs / 20) / (np.sqrt(np.mean(x**2)) + 1e-12)


def room_impulse(rt60: float, rng: np.random.Generator) -> np.ndarray:
    """A synthetic room impulse response: a direct path then exponentially decaying noise."""
    n = int(rt60 * SAMPLE_RATE)
    t = np.arange(n) / SAMPLE_RATE
    tail = rng.normal(size=n) * np.exp(-6.9 * t / rt60) * 0.3
    tail[: int(0.003 * SAMPLE_RATE)] = 0.0
    tail[0] = 1.0
    return tail


def babble(n: int, rng: np.random.Generator, others: list[np.ndarray]) -> np.ndarray:
    """Overlapping speech of other clips: the hardest background noise."""
    out = np.zeros(n)
    for x in others:
        at = int(rng.integers(0, max(1, n - x.size)))
        seg = x[: n - at]
        out[at : at + seg.size] += seg
    return out if np.any(out) else noise("pink", n, rng)


def active_power(speech: np.ndarray) -> float:
    """Mean power of the speech's active part (samples above 5 % of its peak), float ±1 full scale: what noise
    is scaled to for a speech-to-noise ratio, so that silence around a word does not count."""
    active = speech[np.abs(speech) > 0.05 * np.max(np.abs(speech))]
    return float(np.mean(active**2)) if active.size else float(np.mean(speech**2))


def apply(speech: np.ndarray, aug: Augment, rng: np.random.Generator,
          others: list[np.ndarray] | None = None) -> np.ndarray:
    x = speech
    if aug.tempo != 1.0:
        up = 100
        x = resample_poly(x, up, round(up * aug.tempo))
    if aug.reverb_rt60 > 0:
        x = fftconvolve(x, room_impulse(aug.reverb_rt60, rng))[: x.size + int(0.1 * SAMPLE_RATE)]
    x = np.concatenate([np.zeros(int(aug.pad_s[0] * SAMPLE_RATE)), x, np.zeros(int(aug.pad_s[1] * SAMPLE_RATE))])
    if aug.band is not None:
        lo, hi = aug.band
        x = sosfilt(butter(2, [lo, min(hi, 7900.0)], btype="bandpass", fs=SAMPLE_RATE, output="sos"), x)
    x = aug.peak * x / (np.max(np.abs(x)) + 1e-9)
    if aug.noise is not None:
        p = active_power(x)
        bg = babble(x.size, rng, others or []) if aug.noise == "babble" else noise(aug.noise, x.size, rng)
        bg = bg / (np.sqrt(np.mean(bg**2)) + 1e-12)
        x = x + bg * np.sqrt(p / 10 ** (aug.snr_db / 10))
    if aug.floor_dbfs is not None:
        x = x + hiss(x.size, aug.floor_dbfs, rng)
    return x + rng.normal(0.0, 2.0 / 32768.0, x.size)
