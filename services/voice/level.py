"""How loud the input is: a digital gain on what the source gives, and a meter that says when speech reaches the
microphone too quietly for the VAD, too near the noise for the spotter, or so loudly that the sound card clips it.

Measured with `bench/voice_levels.py` (held-out voices, a quiet room's hiss at -70 dBFS; voice README, "How loud the
speech is"): every clip the spotter was trained on peaks between about -26 and -2 dBFS. From a peak of -32 dBFS down,
the live stream's VAD (Silero) starts to miss words, and most of them by -44 dBFS; driven past full scale, clipped
speech is heard less well the harder it clips. A microphone's gain is set in the sound system (`alsamixer`,
`pactl set-source-volume`); where that is not enough or not reachable (a container), `HRI_VOICE_GAIN` adds gain in
the service. Clipping is mended only at the microphone: the service's gain comes after the sound card.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

FULL_SCALE = 32767
"""A sample at or beyond this magnitude (16-bit) is clipped: the sound card had no larger number."""
QUIET_PEAK_DBFS = -32.0
"""Speech peaking below this is quieter than any training clip by 6 dB, and the VAD starts to miss words (7 of 273
held-out words at -32 dBFS, 70 at -38, 208 at -44, in the generator's white hiss; with a microphone's noise spectrum
61, 226 and 304 of 315). Since round voice37d a second VAD hears the stream lifted and finds most of them (0, 3 and 41
of 315), 0.5 s late."""
NOISY_SNR_DB = 20.0
"""An utterance whose speech is less than this over the stream's noise floor (the segmenter's estimate,
`Segment.snr_db`) counts as noisy. On tuning clips (voice README, round voice38) the spotter took 6 % of other words
for commands at about 29 dB by this estimate (speech peaking at -26 dBFS in a quiet room's -70 dBFS hiss), 7.5 % at
about 23 dB (-32 dBFS), 11 % at about 18 dB (-38) and 11.5 % at about 13 dB (-44), and heard fewer commands; a walking
robot's noise at the walking bench's 20 dB is about 17 dB here. Gain does not mend it: it raises the noise with the
speech. A microphone nearer the person does."""
OFFSET_DBFS = -50.0
"""A stream whose samples' mean sits this far from zero or further (dBFS) carries a microphone's DC offset, which the
segmenter takes for the room's noise unless `HRI_VOICE_HIGHPASS` takes it out (voice README, "A microphone's DC
offset"; the level at which `SegmenterConfig.highpass_from_dbfs` switches the high-pass on)."""
CLIPPED_SHARE = 0.001
"""An utterance with more than this share of its samples at full scale counts as clipped."""
MAX_GAIN_DB = 40.0


class LevelError(ValueError):
    """An input gain that is not a number of dB from 0 to `MAX_GAIN_DB`."""


def gain_from(raw: str | float | None) -> float:
    """`HRI_VOICE_GAIN` as dB (None or empty: 0); `LevelError` names the variable and the range. No negative gain:
    the gain comes after the sound card, so it cannot mend a microphone that clips, only make it quieter."""
    if raw is None or (isinstance(raw, str) and not raw.strip()):
        return 0.0
    try:
        db = float(raw)
    except ValueError:
        db = math.nan
    if not 0.0 <= db <= MAX_GAIN_DB:  # NaN fails too
        raise LevelError(f"HRI_VOICE_GAIN={raw!r}: dB of input gain from 0 to {MAX_GAIN_DB:.0f} (e.g. 12 for a quiet "
                         f"microphone; for one that clips, lower its own gain: alsamixer, pactl set-source-volume)")
    return db


def amplify(pcm: bytes, db: float) -> bytes:
    """16-bit PCM with `db` of gain, clipped at full scale as a sound card clips (0 dB: the same bytes)."""
    if db == 0.0 or not pcm:
        return pcm
    x = np.frombuffer(pcm, "<i2").astype(np.float32) * np.float32(10 ** (db / 20))
    return np.clip(np.rint(x), -32768, 32767).astype("<i2").tobytes()


def amplified(chunks: Iterator[bytes], db: float) -> Iterator[bytes]:
    """Each chunk with `db` of gain."""
    for chunk in chunks:
        yield amplify(chunk, db)


def dbfs(value: float) -> float:
    """A 16-bit magnitude as dBFS (full scale 0; silence -inf as -120)."""
    return 20 * math.log10(value / 32768.0) if value > 0 else -120.0


@dataclass(frozen=True)
class Level:
    """One utterance's level."""

    peak_dbfs: float
    clipped: int
    """Samples at full scale."""
    samples: int
    snr_db: float | None = None
    """The speech over the stream's noise floor (the segmenter's estimate; None for a file, which has no floor)."""

    @classmethod
    def of(cls, pcm: bytes, snr_db: float | None = None) -> Level:
        x = np.abs(np.frombuffer(pcm, "<i2").astype(np.int32))
        return cls(dbfs(float(x.max())) if x.size else -120.0, int(np.count_nonzero(x >= FULL_SCALE)), int(x.size),
                   snr_db)

    @property
    def is_clipped(self) -> bool:
        return self.samples > 0 and self.clipped > CLIPPED_SHARE * self.samples

    @property
    def is_quiet(self) -> bool:
        return self.peak_dbfs < QUIET_PEAK_DBFS

    @property
    def is_noisy(self) -> bool:
        return self.snr_db is not None and self.snr_db < NOISY_SNR_DB

    @property
    def kind(self) -> str | None:
        """What is wrong with it, the worst first ("clipped", "quiet", "noisy"), or None."""
        return "clipped" if self.is_clipped else "quiet" if self.is_quiet else "noisy" if self.is_noisy else None

    def advice(self, gain_db: float = 0.0) -> str | None:
        """What to change, or None when the level is fine."""
        if self.is_clipped:
            lower = (f"lower HRI_VOICE_GAIN (now {gain_db:g})" if gain_db > 0 else
                     "lower the microphone's own gain (alsamixer, pactl set-source-volume): clipped audio cannot be "
                     "mended after the sound card")
            return f"the input clips ({self.clipped} samples at full scale): {lower}"
        said = []
        if self.is_quiet:
            said.append(f"speech peaks at {self.peak_dbfs:.0f} dBFS; below {QUIET_PEAK_DBFS:.0f} the VAD hears words late "
                        f"or not at all: "
                         f"{_raise(self.peak_dbfs, gain_db)}")
        if self.is_noisy:
            said.append(f"speech is only {self.snr_db:.0f} dB over the noise floor; below {NOISY_SNR_DB:.0f} the spotter "
                        f"hears fewer commands and takes more other words for them: bring the microphone nearer the "
                        f"person, or quiet the room (gain raises the noise with the speech)")
        return "; and ".join(said) or None


@dataclass
class Meter:
    """The stream's loudest moment and its noise floor over the last `window_s` seconds (fed 30 ms chunks), and the
    utterances' levels: what the voice service's health shows."""

    window_s: float = 10.0
    chunk_s: float = 0.03
    report: Callable[[dict[str, object]], None] | None = None
    """Called with `detail()` every `report_s` of audio fed (from the thread that feeds the meter)."""
    report_s: float = 2.0
    _peaks: deque[float] = field(default_factory=deque)
    _rms: deque[float] = field(default_factory=deque)
    _means: deque[float] = field(default_factory=deque)
    utterances: int = 0
    quiet: int = 0
    clipped: int = 0
    noisy: int = 0
    last: Level | None = None
    _fed: int = 0

    def feed(self, chunk: bytes) -> None:
        x = np.frombuffer(chunk, "<i2").astype(np.float32)
        if not x.size:
            return
        keep = max(1, round(self.window_s / self.chunk_s))
        self._peaks.append(float(np.abs(x).max()))  # as it came: how near full scale the sound card is
        self._rms.append(float(np.std(x)))  # a microphone's DC offset is no noise (the segmenter's high-pass takes it out)
        self._means.append(float(x.mean()))
        while len(self._peaks) > keep:
            self._peaks.popleft()
            self._rms.popleft()
            self._means.popleft()
        self._fed += 1
        if self.report is not None and self._fed % max(1, round(self.report_s / self.chunk_s)) == 0:
            self.report(self.detail())

    def metered(self, chunks: Iterator[bytes]) -> Iterator[bytes]:
        """`chunks` unchanged, each fed to the meter on its way."""
        for chunk in chunks:
            self.feed(chunk)
            yield chunk

    def utterance(self, pcm: bytes, snr_db: float | None = None) -> Level:
        level = Level.of(pcm, snr_db)
        self.utterances += 1
        self.quiet += level.is_quiet
        self.clipped += level.is_clipped
        self.noisy += level.is_noisy
        self.last = level
        return level

    def detail(self) -> dict[str, object]:
        """Health fields: the stream's peak and floor (dBFS) over the window, and the utterances' counts."""
        out: dict[str, object] = {"quiet_utterances": self.quiet, "clipped_utterances": self.clipped,
                                  "noisy_utterances": self.noisy}
        if self._peaks:
            out["input_peak_dbfs"] = round(dbfs(max(self._peaks)), 1)
            out["input_floor_dbfs"] = round(dbfs(float(np.percentile(self._rms, 10))), 1)
            out["input_offset_dbfs"] = round(dbfs(abs(float(np.median(self._means)))), 1)
        if self.last is not None:
            out["last_peak_dbfs"] = round(self.last.peak_dbfs, 1)
        return out


def offset_advice(detail: Mapping[str, object], highpass: bool) -> str | None:
    """What to change for a DC offset in the stream (`Meter.detail()`'s `input_offset_dbfs` at `OFFSET_DBFS` or
    further) that the high-pass (`highpass`: on) is not taking out; None: nothing."""
    offset = detail.get("input_offset_dbfs")
    if highpass or not isinstance(offset, float) or offset < OFFSET_DBFS:
        return None
    return (f"the microphone hands its samples over with a DC offset ({offset:.0f} dBFS), which the VAD takes for "
            f"noise: set HRI_VOICE_HIGHPASS=30 (the default) to take it out")


def verdict(meter: Meter, levels: list[Level], gain_db: float = 0.0, highpass: bool = False) -> str:
    """`python -m services.voice level`'s last line: what to change, judged on the utterances the VAD found, or, when
    it found none, on the loudest moment of the stream over its floor; first of all, a DC offset the high-pass
    (`highpass`: on) is not taking out."""
    offset = offset_advice(meter.detail(), highpass)
    if offset is not None:
        return f"{offset}, then check again"
    clipped = [lv for lv in levels if lv.is_clipped]
    if clipped:
        return clipped[0].advice(gain_db) or ""
    if levels:
        loudest = max(levels, key=lambda lv: lv.peak_dbfs)
        over = f", {loudest.snr_db:.0f} dB over the noise" if loudest.snr_db is not None else ""
        return loudest.advice(gain_db) or (f"fine: speech peaks at {loudest.peak_dbfs:.0f} dBFS (the spotter was "
                                           f"trained on -26 to -2){over}")
    detail = meter.detail()
    if "input_peak_dbfs" not in detail:
        return "no audio"
    peak, floor = float(detail["input_peak_dbfs"]), float(detail["input_floor_dbfs"])  # type: ignore[arg-type]
    if peak - floor < 12.0:
        return f"no speech found: nothing rose above the floor ({floor:.0f} dBFS; loudest {peak:.0f}). Is it the " \
               f"right microphone, and is it muted?"
    return (f"no speech found; the loudest sound peaked at {peak:.0f} dBFS over a floor of {floor:.0f}. If that was "
            f"you, it is too quiet for the VAD: {_raise(peak, gain_db)}")


def _raise(peak_dbfs: float, gain_db: float) -> str:
    """What brings speech peaking at `peak_dbfs` (with `gain_db` set) to `QUIET_PEAK_DBFS` + 12 dB (-20 dBFS)."""
    want = gain_db + max(0, math.ceil(QUIET_PEAK_DBFS + 12 - peak_dbfs))
    if want > MAX_GAIN_DB:
        return f"raise the microphone's own gain, or bring it nearer (HRI_VOICE_GAIN={want:g} would be over its {MAX_GAIN_DB:g})"
    return f"raise the microphone's gain, or set HRI_VOICE_GAIN={want:g}"
