"""The voice service: utterances from a source -> recogniser -> one `VoiceCommand` per utterance.

Publishes on `hri/<robot>/voice/command`. `command` is set only when the engine's acceptance test
passed; otherwise it is null and `text` says what was heard. A source that cannot be opened (no
PortAudio, no microphone, missing folder) turns health `degraded`, naming the source and the
alternatives, and is retried with back-off (`retry_s`, doubling up to `max_retry_s`; one warning per
new error, not one per retry); the service keeps running. Invalid configuration (unknown engine,
unreadable lexicon or head file) is found by `check_settings` before the service starts: exit 2.
A file or folder source that has been read to the end leaves the service idle (health detail
`source: finished`).
"""

from __future__ import annotations

import contextlib
import math
import os
import queue
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from schemas.messages import Command, Decision, HealthStatus, SpeechState, VoiceCommand
from services.runtime import ServiceContext, default_state_dir
from services.runtime.flags import parse_flag
from services.voice.audio import SAMPLE_RATE, AudioError
from services.voice.echo import ENV as ECHO_ENV
from services.voice.echo import (
    FIT_ENV,
    MEMORY_ENV,
    MEMORY_FILE,
    EchoCanceller,
    EchoError,
    EchoMemory,
    Played,
    echo_cancel_from,
    echo_fit_from,
    echo_memory_from,
)
from services.voice.engine import (
    DEFAULT_ENGINE,
    Engine,
    EngineError,
    Recognition,
    check_engine_name,
    make_engine,
    one_blas_thread,
)
from services.voice.level import LevelError, Meter, dbfs, gain_from, offset_advice
from services.voice.mic import MicError, MicFormat
from services.voice.own_voice import (
    OWN_STOP_ENV,
    OwnVoice,
    OwnVoiceError,
    own_stop_from,
    said_stop,
    tail_from,
)
from services.voice.pacing import CommandPacer
from services.voice.robot_voice import RobotVoice
from services.voice.segmenter import VADS, SegmenterConfig
from services.voice.sources import ALTERNATIVES, SourceError, SourceSpec, Utterance, utterances
from services.voice.vad import VadError, silero_model_path

NAME = "voice"
ADVICE_EVERY_S = 60.0
"""The input level's advice (too quiet, clipped) is logged at most this often for each kind."""
SPEECH_ASK_S = 2.0
"""How long the start-up question to the speech service (is the robot talking?) waits for an answer."""


@dataclass(frozen=True)
class VoiceSettings:
    source: str = "mic"
    engine: str = DEFAULT_ENGINE
    vosk_model: str | None = None
    lexicon: str | None = None
    head: str | None = None
    """Spotter head file; None: the enrolled head in the state folder if there is one, else the committed one."""
    walk_gate: str | None = None
    """Spotter walk gate (`engine_spotter.walk_gate_for`): a head file, `none`, or None for the default."""
    agree_min: str | None = None
    """`HRI_VOICE_AGREE_MIN`: the spotter's agreement veto (`engine_spotter.agree_min_from`); None: the default."""
    decoder: str | None = None
    """`HRI_VOICE_DECODER`: the spotter's second opinion from Whisper's decoder, on or off
    (`engine_spotter.decoder_from`); None: the default."""
    stop_in_phrase: str | None = None
    """`HRI_VOICE_STOP_IN_PHRASE`: the spotter also looks for "stop" within a phrase, on or off
    (`engine_spotter.stop_in_phrase_from`); None: the default."""
    stop_in_long: str | None = None
    """`HRI_VOICE_STOP_IN_LONG`: the spotter also looks for "stop" within an utterance longer than one command word,
    on or off (`engine_spotter.stop_in_long_from`); None: the default."""
    warped_look: str | None = None
    """`HRI_VOICE_WARPED_LOOK`: the spotter hears an utterance it came near to accepting again at other speeds, on or
    off (`engine_spotter.warped_look_from`); None: the default."""
    down_in_phrase: str | None = None
    """`HRI_VOICE_DOWN_IN_PHRASE`: the spotter also hears "down" within a phrase ("sit down"), on or off
    (`engine_spotter.down_in_phrase_from`); None: the default."""
    vad: str = "silero"
    """The live stream's voice activity detector (`segmenter.VADS`); files are always trimmed with WebRTC's."""
    early_look: str | None = None
    """`HRI_VOICE_EARLY_LOOK`: seconds of quiet before the segmenter's early look (`SegmenterConfig.early_quiet_s`),
    or `off`; None: the default."""
    clear_window: str | None = None
    """`HRI_VOICE_CLEAR_WINDOW`: seconds of quiet that end an utterance in a clear stream
    (`SegmenterConfig.clear_quiet_s`), or `off`; None: the default."""
    vad_lift: str | None = None
    """`HRI_VOICE_VAD_LIFT`: the peak (dBFS) a quiet live stream is lifted to for the second VAD
    (`SegmenterConfig.vad_lift_dbfs`), or `off`; None: the default (-20)."""
    vad_reset: str | None = None
    """`HRI_VOICE_VAD_RESET`: seconds of a live stream outside utterances after which Silero's state starts again,
    warmed on them (`SegmenterConfig.vad_reset_s`), or `off`; None: the default."""
    vad_fresh_end: str | None = None
    """`HRI_VOICE_VAD_FRESH_END`: seconds of a live stream outside utterances after which a second Silero state starts
    again to end the words it hears (`SegmenterConfig.vad_fresh_end_s`), or `off`; None: the default."""
    vad_fresh_end_snr: str | None = None
    """`HRI_VOICE_VAD_FRESH_END_SNR`: how far (dB) an utterance's speech must be over the noise floor for the second
    state to end it (`SegmenterConfig.vad_fresh_end_snr_db`), or `off` (every utterance it heard); None: the default."""
    floor_hold: str | None = None
    """`HRI_VOICE_FLOOR_HOLD`: the segmenter's noise floor held while the echo canceller says the robot's voice lies in
    the stream (`SegmenterConfig.floor_hold`), `on`, `off` or `after` (held, but judging an utterance only once the
    robot's voice has passed: `SegmenterConfig.floor_hold_after`); None: the default (`after`, round voice51c; `on`,
    held throughout, did not pass rounds voice51 and 51b)."""
    highpass: str | None = None
    """`HRI_VOICE_HIGHPASS`: the live stream's high-pass (Hz) before the VAD, switched on once the stream shows a DC
    offset, which it takes out (`SegmenterConfig.highpass_hz`, `highpass_from_dbfs`), or `off`; None: the default (30 Hz)."""
    gain: str | None = None
    """`HRI_VOICE_GAIN`: dB of gain on the source's audio before the VAD (`level.gain_from`); None: 0."""
    mic_rate: str | None = None
    """`HRI_VOICE_MIC_RATE`: the rate (Hz) to open a microphone at (`mic.MicFormat`); None: 16 kHz, or the device's."""
    mic_channels: str | None = None
    """`HRI_VOICE_MIC_CHANNELS`: the channels to open a microphone with, mixed down to one; None: 1, or else 2."""
    own_voice: str | None = None
    """`HRI_VOICE_OWN_VOICE`: a live source's utterances that overlap the robot's own voice are not published, "stop"
    excepted (`own_voice.tail_from`: `ignore`, `hear`, or the tail in seconds); None: `ignore`."""
    own_stop: str | None = None
    """`HRI_VOICE_OWN_STOP`: with the echo canceller, a "stop" whose speech began where the robot itself says "stop" is
    not published (`own_voice.said_stop`), `ignore` or `hear`; None: the default (`own_voice.OWN_STOP_DEFAULT`)."""
    echo_cancel: str | None = None
    """`HRI_VOICE_ECHO_CANCEL`: a live source's stream has the robot's own voice cancelled (`echo.EchoCanceller`),
    `on` or `off`; None: on."""
    echo_memory: str | None = None
    """`HRI_VOICE_ECHO_MEMORY`: the canceller's memory of the robot's voice kept in the state folder and recalled at
    start (`echo.EchoMemory`), `on` or `off`; None: the default (`echo.MEMORY_DEFAULT_ON`)."""
    echo_fit: str | None = None
    """`HRI_VOICE_ECHO_FIT`: the canceller subtracts a way from the loudspeaker fitted on its memory before its adaptive
    filter (`echo.EchoCanceller.fit`, `echo_fit`), `on` or `off`; None: the default (`echo.FIT_DEFAULT_ON`)."""
    retry_s: float = 2.0
    max_retry_s: float = 30.0

    @classmethod
    def from_env(cls) -> VoiceSettings:
        return cls(
            source=os.environ.get("HRI_VOICE_SOURCE") or "mic",
            engine=os.environ.get("HRI_VOICE_ENGINE") or DEFAULT_ENGINE,
            vosk_model=os.environ.get("HRI_VOSK_MODEL") or None,
            lexicon=os.environ.get("HRI_VOICE_LEXICON") or None,
            head=os.environ.get("HRI_VOICE_HEAD") or None,
            walk_gate=os.environ.get("HRI_VOICE_WALK_GATE") or None,
            agree_min=os.environ.get("HRI_VOICE_AGREE_MIN") or None,
            decoder=os.environ.get("HRI_VOICE_DECODER") or None,
            stop_in_phrase=os.environ.get("HRI_VOICE_STOP_IN_PHRASE") or None,
            stop_in_long=os.environ.get("HRI_VOICE_STOP_IN_LONG") or None,
            warped_look=os.environ.get("HRI_VOICE_WARPED_LOOK") or None,
            down_in_phrase=os.environ.get("HRI_VOICE_DOWN_IN_PHRASE") or None,
            vad=os.environ.get("HRI_VOICE_VAD") or "silero",
            early_look=os.environ.get("HRI_VOICE_EARLY_LOOK") or None,
            clear_window=os.environ.get("HRI_VOICE_CLEAR_WINDOW") or None,
            vad_lift=os.environ.get("HRI_VOICE_VAD_LIFT") or None,
            vad_reset=os.environ.get("HRI_VOICE_VAD_RESET") or None,
            vad_fresh_end=os.environ.get("HRI_VOICE_VAD_FRESH_END") or None,
            vad_fresh_end_snr=os.environ.get("HRI_VOICE_VAD_FRESH_END_SNR") or None,
            floor_hold=os.environ.get("HRI_VOICE_FLOOR_HOLD") or None,
            highpass=os.environ.get("HRI_VOICE_HIGHPASS") or None,
            gain=os.environ.get("HRI_VOICE_GAIN") or None,
            mic_rate=os.environ.get("HRI_VOICE_MIC_RATE") or None,
            mic_channels=os.environ.get("HRI_VOICE_MIC_CHANNELS") or None,
            own_voice=os.environ.get("HRI_VOICE_OWN_VOICE") or None,
            own_stop=os.environ.get(OWN_STOP_ENV) or None,
            echo_cancel=os.environ.get(ECHO_ENV) or None,
            echo_memory=os.environ.get(MEMORY_ENV) or None,
            echo_fit=os.environ.get(FIT_ENV) or None,
        )

    def mic(self) -> MicFormat:
        """The format to open a microphone at; `EngineError` names a bad `HRI_VOICE_MIC_*` value."""
        try:
            return MicFormat.parse(self.mic_rate, self.mic_channels)
        except MicError as exc:
            raise EngineError(str(exc)) from None

    def segmenter(self) -> SegmenterConfig:
        """The live stream's segmenter; `EngineError` for an early look or a clear window that is not `off` or
        seconds shorter than the end window, a VAD lift, a VAD reset or a high-pass out of its range, or a floor hold
        that is not on, off or after."""
        base = SegmenterConfig(vad=self.vad)
        floor_hold: bool | None
        if self.floor_hold is None:
            floor_hold, after = base.floor_hold, base.floor_hold_after
        elif self.floor_hold.strip().lower() == "after":
            floor_hold, after = True, True
        else:  # on: held throughout; off: not held
            floor_hold, after = parse_flag(self.floor_hold), False
        if floor_hold is None:
            raise EngineError(f"HRI_VOICE_FLOOR_HOLD={self.floor_hold!r}: on, off or after")

        def quiet_s(value: float) -> bool:
            return 0.0 < value < base.quiet_s

        shorter = f"seconds of quiet above 0 and below the end window ({base.quiet_s} s)"
        return replace(base,
                       early_quiet_s=_off_or(quiet_s, shorter, "HRI_VOICE_EARLY_LOOK", self.early_look,
                                             base.early_quiet_s),
                       clear_quiet_s=_off_or(quiet_s, shorter, "HRI_VOICE_CLEAR_WINDOW", self.clear_window,
                                             base.clear_quiet_s),
                       vad_lift_dbfs=_off_or(lambda v: -40.0 <= v <= 0.0, "the peak level (dBFS) a quiet stream is "
                                             "lifted to for the VAD, from -40 to 0", "HRI_VOICE_VAD_LIFT",
                                             self.vad_lift, base.vad_lift_dbfs),
                       vad_reset_s=_off_or(lambda v: 0.3 <= v <= 60.0, "seconds from 0.3 to 60 of a stream outside "
                                           "utterances after which the VAD's state starts again",
                                           "HRI_VOICE_VAD_RESET", self.vad_reset, base.vad_reset_s),
                       vad_fresh_end_s=_off_or(lambda v: 0.3 <= v <= 60.0, "seconds from 0.3 to 60 of a stream "
                                               "outside utterances after which the VAD's second state starts again",
                                               "HRI_VOICE_VAD_FRESH_END", self.vad_fresh_end, base.vad_fresh_end_s),
                       vad_fresh_end_snr_db=_off_or(lambda v: 0.0 <= v <= 60.0, "dB from 0 to 60 of speech over the "
                                                    "noise floor from which the VAD's second state ends an utterance",
                                                    "HRI_VOICE_VAD_FRESH_END_SNR", self.vad_fresh_end_snr,
                                                    base.vad_fresh_end_snr_db),
                       floor_hold=floor_hold, floor_hold_after=after,
                       highpass_hz=_off_or(lambda v: 1.0 <= v <= 300.0, "the high-pass's frequency (Hz) from 1 to 300",
                                           "HRI_VOICE_HIGHPASS", self.highpass, base.highpass_hz))


def _off_or(ok: Callable[[float], bool], what: str, variable: str, raw: str | None,
            default: float | None) -> float | None:
    """`raw` as a number for which `ok` holds (`EngineError` naming the variable and `what` otherwise); `off` -> None;
    None -> `default`."""
    if raw is None:
        return default
    if raw.strip().lower() == "off":
        return None
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if math.isnan(value) or not ok(value):
        raise EngineError(f"{variable}={raw!r}: 'off' or {what}")
    return value


def check_settings(settings: VoiceSettings) -> None:
    """Raise `EngineError` for configuration that can never work (so the service exits 2 at start);
    a missing device or model that may appear later is not checked here (it is retried)."""
    check_engine_name(settings.engine)
    if settings.vad not in VADS:
        raise EngineError(f"HRI_VOICE_VAD={settings.vad!r}: one of {', '.join(VADS)}")
    settings.segmenter()
    settings.mic()
    try:
        gain_from(settings.gain)
        tail_from(settings.own_voice)
        own_stop_from(settings.own_stop)
        echo_cancel_from(settings.echo_cancel)
        echo_memory_from(settings.echo_memory)
        echo_fit_from(settings.echo_fit)
    except (LevelError, OwnVoiceError, EchoError) as exc:
        raise EngineError(str(exc)) from None
    if settings.vad == "silero":  # the model ships in a core dependency: missing means a broken install
        try:
            silero_model_path()
        except VadError as exc:
            raise EngineError(str(exc)) from None
    if settings.lexicon:
        from services.voice.lexicon import Lexicon, LexiconError

        try:
            Lexicon.load(settings.lexicon)
        except LexiconError as exc:
            raise EngineError(str(exc)) from None
    if settings.engine == "spotter":
        from services.voice.engine_spotter import (
            NO_GATE,
            agree_min_from,
            decoder_from,
            down_in_phrase_from,
            stop_in_long_from,
            stop_in_phrase_from,
            warped_look_from,
        )

        agree_min_from(settings.agree_min)
        decoder_from(settings.decoder)
        stop_in_phrase_from(settings.stop_in_phrase)
        stop_in_long_from(settings.stop_in_long)
        warped_look_from(settings.warped_look)
        down_in_phrase_from(settings.down_in_phrase)
        from services.voice.spotter.head import Head, HeadError

        files = {"HRI_VOICE_HEAD": settings.head,
                 "HRI_VOICE_WALK_GATE": settings.walk_gate if settings.walk_gate != NO_GATE else None}
        for variable, path in files.items():
            try:
                if path:
                    Head.load(path)
            except HeadError as exc:
                raise EngineError(f"{variable}: {exc}") from None


@dataclass
class _Stats:
    utterances: int = 0
    accepted: int = 0
    rejected: int = 0
    bad_audio: int = 0
    early_looks: int = 0
    """Utterances decoded at the segmenter's early look (each also counts in `decode_s`)."""
    early_taken: int = 0
    """Of them, the utterances that ended there (a command accepted confidently enough)."""
    own_voice: int = 0
    """Utterances not published: they overlapped the robot's own voice (`own_voice.OwnVoice`)."""
    own_stop: int = 0
    """The "stop"s not published: they began where the robot itself said "stop" (`own_voice.said_stop`)."""
    decode_s: float = 0.0
    audio_s: float = 0.0

    def as_detail(self) -> dict[str, object]:
        return {
            "utterances": self.utterances, "accepted": self.accepted, "rejected_speech": self.rejected,
            "bad_audio": self.bad_audio, "early_looks": self.early_looks, "early_taken": self.early_taken,
            "own_voice_dropped": self.own_voice, "own_stop_dropped": self.own_stop,
            "real_time_factor": round(self.decode_s / self.audio_s, 4) if self.audio_s else None,
        }


def serve(ctx: ServiceContext, settings: VoiceSettings | None = None) -> None:
    settings = settings or VoiceSettings.from_env()
    segmenter = settings.segmenter()
    blas_threads = one_blas_thread()  # the whole process, before any engine multiplies a matrix
    silero = settings.vad == "silero"  # the settings below are Silero's alone
    ctx.update_detail(source=settings.source, engine=settings.engine, vad=settings.vad, blas_threads=blas_threads,
                      gain_db=gain_from(settings.gain),
                      early_look_s=segmenter.early_quiet_s,
                      clear_window_s=segmenter.clear_quiet_s if silero else None,
                      vad_lift_dbfs=segmenter.vad_lift_dbfs if silero else None,
                      vad_reset_s=segmenter.vad_reset_s if silero else None,
                      vad_fresh_end_s=segmenter.vad_fresh_end_s if silero else None,
                      vad_fresh_end_snr_db=segmenter.vad_fresh_end_snr_db if silero else None,
                      floor_hold=segmenter.floor_hold if silero else None,
                      floor_hold_after=segmenter.floor_hold_after if silero else None,
                      highpass_hz=segmenter.highpass_hz)
    # Before the engine loads (seconds): a sentence the robot begins meanwhile is still its own once listening starts.
    own, echo = _robot_voice(ctx, settings)
    # The source may block (stdin, a silent microphone): it runs on its own daemon thread so that
    # SIGTERM always stops the service promptly.
    listener = ctx.thread(lambda: _listen(ctx, settings, own, echo), "listen")
    ctx.on_close(lambda: listener.join(timeout=3.0))
    while not ctx.wait(1.0):
        pass


def _listen(ctx: ServiceContext, settings: VoiceSettings, own: OwnVoice | None, echo: _Echo | None) -> None:
    engine = _engine_until_ready(ctx, settings)
    if engine is None:
        return
    # Congestion blocks rather than drops (as for motion goals): a spoken command, "stop" included,
    # is one message per utterance and must not vanish on a busy link; listening waits meanwhile.
    pub = ctx.publisher(ctx.keys.voice_command, VoiceCommand, block=True)
    # the reasoner's answers pace the puts, so that the router's input limit never takes two commands for a flood
    decisions = ctx.polled(ctx.keys.reasoner_decision, Decision)
    pacer = CommandPacer(lambda: [d.cause_stamp for d in decisions()])
    stats = _Stats()
    gain_db = gain_from(settings.gain)
    pre_roll_s = settings.segmenter().pre_roll_s
    own_stop = own_stop_from(settings.own_stop)
    advised: dict[str, float] = {}
    highpass = settings.segmenter().highpass_hz is not None

    def advise(kind: str, advice: str, **fields: object) -> None:
        """Once a minute at most for each kind: a user who cannot change it now is not flooded."""
        if time.monotonic() - advised.get(kind, -ADVICE_EVERY_S) >= ADVICE_EVERY_S:
            advised[kind] = time.monotonic()
            ctx.log.warning("input level", advice=advice, **fields)

    def echo_detail() -> dict[str, object]:
        return echo.detail() if echo is not None else {}

    def on_level(detail: dict[str, object]) -> None:
        ctx.update_detail(**detail, **echo_detail())  # every 2 s of a live stream
        advice = offset_advice(detail, highpass)  # a DC offset hides quiet speech, and nothing in a word says so
        if advice is not None:
            advise("offset", advice)

    # the input's level (health, every 2 s of a live stream), and advice when speech is too quiet or clips
    meter = Meter(report=on_level)
    mic = settings.mic()

    def mic_opened(rate: int, channels: int) -> None:
        ctx.update_detail(mic_rate_hz=rate, mic_channels=channels)
        ctx.log.info("microphone opened", source=settings.source, rate_hz=rate, channels=channels,
                     resampled=rate != SAMPLE_RATE or channels != 1)

    def on_highpass(on: bool, offset: float) -> None:
        ctx.update_detail(highpass_on=on)
        if on and offset > 0:  # once per stream: the microphone has an offset, and from here it is taken out
            ctx.log.info("high-pass switched on: the stream has a DC offset",
                         offset_dbfs=round(dbfs(offset * 32768.0), 1), highpass_hz=settings.segmenter().highpass_hz)

    def on_bad_file(path: Path, exc: AudioError) -> None:
        stats.bad_audio += 1
        ctx.log.warning("bad audio skipped", file=str(path), error=str(exc))
        ctx.update_detail(**stats.as_detail(), last_error=str(exc))

    def early_look(pcm: bytes) -> Recognition:
        """The segmenter's early look. A decoder error here is not the utterance's end: the segmenter waits for
        the whole utterance, and `handle` decodes (or reports) it."""
        stats.early_looks += 1
        try:
            rec = engine.recognise(pcm)
        except Exception as exc:  # any of the decoders' own error types (pocketsphinx raised IndexError)
            return Recognition(None, "(early look failed)", 0.0, engine.name, detail={"reason": repr(exc)})
        stats.decode_s += rec.decode_s
        return rec

    def handle(utt: Utterance) -> None:
        rec = utt.recognition
        if rec is not None:
            stats.early_taken += 1
        else:
            try:
                rec = engine.recognise(utt.pcm)
            except Exception as exc:  # a decoder error on odd audio, of any type: skip it, keep listening
                stats.bad_audio += 1
                ctx.log.warning("decode failed", origin=utt.origin, error=repr(exc))
                return
            stats.decode_s += rec.decode_s
        stats.utterances += 1
        stats.audio_s += rec.audio_s
        level = meter.utterance(utt.pcm, utt.snr_db)
        advice = level.advice(gain_db)
        if advice is not None:
            advise(level.kind or "", advice, origin=utt.origin)
        # the utterance from its speech's onset (its audio begins `pre_roll_s` before) to when it was cut, wall clock
        began = utt.began if utt.began is not None else utt.stamp - utt.seconds
        onset = min(began + pre_roll_s, utt.stamp)
        if rec.command is Command.STOP and own_stop and echo is not None and said_stop(
                echo.canceller.played.sentences(), onset):
            stats.own_stop += 1  # the robot's own "stop", where the canceller placed its sentence: not a person's
            ctx.log.info("heard where the robot itself said 'stop': not published", origin=utt.origin, text=rec.text,
                         confidence=round(rec.confidence, 3))
            ctx.update_detail(**stats.as_detail(), **echo_detail())
            return
        if own is not None and rec.command is not Command.STOP and own.overlaps(onset, utt.stamp):
            stats.own_voice += 1  # the robot's own voice, most likely: publishing it would make the robot answer itself
            ctx.log.info("heard while the robot spoke: not published", origin=utt.origin,
                         command=rec.command.value if rec.command else None, text=rec.text,
                         confidence=round(rec.confidence, 3))
            ctx.update_detail(**stats.as_detail(), **echo_detail())
            return
        if rec.command is None:
            stats.rejected += 1
        else:
            stats.accepted += 1
        message = rec.message(stamp=utt.stamp)
        pacer.turn()
        pacer.put(message.stamp)
        msg = pub.put(message)
        ctx.log.info("heard", origin=utt.origin, command=msg.command.value if msg.command else None,
                     text=msg.text, confidence=msg.confidence, decode_ms=round(rec.decode_s * 1000, 1),
                     latency_ms=round((time.time() - utt.stamp) * 1000, 1), early=utt.recognition is not None,
                     snr_db=round(utt.snr_db, 1) if utt.snr_db is not None else None,
                     peak_dbfs=round(level.peak_dbfs, 1), **rec.detail)
        # the stream's last speech-to-noise estimate: whether the room counts as clear (`clear_window_s`)
        ctx.update_detail(**stats.as_detail(), **meter.detail(), **echo_detail(), **pacer.detail(),
                          **({"last_snr_db": round(utt.snr_db, 1)} if utt.snr_db is not None else {}))

    delay, last_error = settings.retry_s, ""
    while not ctx.stopping.is_set():
        try:
            spec = SourceSpec.parse(settings.source)
            for utt in utterances(spec, ctx.stopping.is_set, on_error=on_bad_file,
                                  segmenter=settings.segmenter(), recognise=early_look, gain_db=gain_db, meter=meter,
                                  mic=mic, mic_opened=mic_opened, on_highpass=on_highpass,
                                  echo=echo.canceller if echo is not None else None):
                if ctx.status != HealthStatus.OK:
                    ctx.set_status(HealthStatus.OK, source_error=None)
                    ctx.log.info("voice source available", source=settings.source)
                delay, last_error = settings.retry_s, ""
                handle(utt)
        except (SourceError, AudioError) as exc:
            ctx.set_status(HealthStatus.DEGRADED, source_error=str(exc), alternatives=ALTERNATIVES,
                           retry_in_s=delay)
            if str(exc) != last_error:  # one warning per new error; the retries are in health
                ctx.log.warning("voice source unavailable, retrying with back-off", source=settings.source,
                                error=str(exc), alternatives=ALTERNATIVES)
                last_error = str(exc)
            ctx.wait(delay)
            delay = min(delay * 2, settings.max_retry_s)
            continue
        if not ctx.stopping.is_set():
            ctx.log.info("source finished", source=settings.source)
            ctx.update_detail(source_state="finished")
            ctx.stopping.wait()


@dataclass
class _Echo:
    """A live stream's echo canceller and the renderer of its reference."""

    canceller: EchoCanceller
    voice: RobotVoice

    def detail(self) -> dict[str, object]:
        c = self.canceller
        return {"echo_frames": c.frames, "echo_locked": c.locked, "echo_lost": c.lost, "echo_lag_ms_last": c.lag_ms,
                "echo_erle_db_last": c.erle_db, "echo_held_ms_last": c.held_ms, "echo_recalled_s": c.recalled_s,
                "echo_fits": c.fits, "echo_fit_db_last": c.fit_db, "echo_fit_ms_last": c.fit_ms,
                **self.voice.detail()}


def _robot_voice(ctx: ServiceContext, settings: VoiceSettings) -> tuple[OwnVoice | None, _Echo | None]:
    """For a live source (a microphone, a stream on stdin), the robot's own voice as the speech service reports it
    (None with `HRI_VOICE_OWN_VOICE=hear`), and its echo canceller (None with `HRI_VOICE_ECHO_CANCEL=off`, or where it
    cannot run); neither for recordings (files, folders, a spool), which cannot hear the robot. Subscribed at once,
    before the engine loads: a sentence the robot begins meanwhile is still its own once listening starts."""
    tail, cancel = tail_from(settings.own_voice), echo_cancel_from(settings.echo_cancel)
    try:
        live = SourceSpec.parse(settings.source).kind in ("mic", "stdin")
    except SourceError:
        live = False  # the listener reports the bad source
    if not live:
        ctx.update_detail(own_voice="not a live source", echo_cancel="not a live source")
        return None, None
    own = OwnVoice(tail_s=tail) if tail is not None else None
    echo: _Echo | None = None
    memory_detail: dict[str, object] = {}
    if cancel:
        try:
            played = Played()
            speech_detail = lambda: (h := ctx.query_health("speech", timeout=1.0)) and h.detail  # noqa: E731
            echo = _Echo(EchoCanceller(played, fit=echo_fit_from(settings.echo_fit), background=True),
                         RobotVoice(played, speech_detail))
            memory_detail = _echo_memory(ctx, settings, echo.canceller)
        except EchoError as exc:
            ctx.update_detail(echo_cancel=f"unavailable: {exc}")
            ctx.log.warning("echo canceller unavailable: the robot's own voice is not cancelled", error=str(exc))
    if own is not None or echo is not None:
        ctx.subscribe(ctx.keys.speech_state, SpeechState, lambda state: _robot_said(state, own, echo))
    if echo is not None:
        c = echo.canceller
        ctx.update_detail(echo_cancel="on", echo_fit="on" if c.fit else "off", echo_fits=c.fits,
                          echo_fit_db_last=c.fit_db,
                          own_stop="ignored" if own_stop_from(settings.own_stop) else "heard", **memory_detail)
        ctx.thread(lambda: echo.voice.run(ctx.stopping), "echo-reference")
    elif not cancel:
        ctx.update_detail(echo_cancel="off")
    if own is None:
        ctx.update_detail(own_voice="heard")
    else:
        ctx.update_detail(own_voice="ignored", own_voice_tail_s=tail)
        ctx.thread(lambda: _ask_speaking(ctx, own), "own-voice")  # after subscribing: a newer state wins over it
    return own, echo


def _echo_memory(ctx: ServiceContext, settings: VoiceSettings, canceller: EchoCanceller) -> dict[str, object]:
    """With `HRI_VOICE_ECHO_MEMORY` on: the canceller recalls the memory an earlier run kept in the state folder (an
    unreadable one is passed over with a warning, and the canceller starts cold, as on a first run; it is overwritten
    once the robot has spoken) and keeps its own there each time the robot falls silent. Returns its health detail,
    for the caller to publish with the canceller's own in one update (health is never seen half-filled)."""
    if not echo_memory_from(settings.echo_memory):
        return {"echo_memory": "off"}
    memory = EchoMemory(default_state_dir(ctx.keys.robot) / MEMORY_FILE)
    detail: dict[str, object] = {}
    try:
        if memory.recall(canceller):
            ctx.log.info("echo memory recalled", path=str(memory.path), seconds=canceller.recalled_s)
    except (OSError, ValueError) as exc:
        ctx.log.warning("echo memory unusable: the canceller starts cold", path=str(memory.path), error=str(exc))
        detail["echo_memory_warning"] = f"unusable, starting cold: {exc}"
    # written on a thread of its own: the stream's thread only copies the memory (a robot's SD card can stall a write
    # for longer than a "stop" should wait); a newer memory replaces one not yet written
    latest: queue.Queue[tuple[np.ndarray, np.ndarray]] = queue.Queue(maxsize=1)

    def keep(c: EchoCanceller) -> None:
        with contextlib.suppress(queue.Empty):
            latest.get_nowait()
        latest.put_nowait(c.memory())

    def write() -> None:
        warned = False
        while not ctx.stopping.is_set() or not latest.empty():
            try:
                snapshot = latest.get(timeout=0.5)
            except queue.Empty:
                continue
            try:
                memory.write(snapshot)
            except OSError as exc:
                if not warned:  # once: the stream goes on, only the next run starts cold
                    ctx.log.warning("echo memory not saved", path=str(memory.path), error=str(exc))
                    ctx.update_detail(echo_memory_warning=f"not saved: {exc}")
                    warned = True

    canceller.on_silent = keep
    writer = ctx.thread(write, "echo-memory")
    ctx.on_close(lambda: writer.join(timeout=2.0))  # the last memory written before the process exits
    return {**detail, "echo_memory": "on", "echo_memory_path": str(memory.path), "echo_recalled_s": canceller.recalled_s}


def _robot_said(state: SpeechState, own: OwnVoice | None, echo: _Echo | None) -> None:
    if own is not None:
        own.heard(state.speaking)
    if echo is not None:
        echo.voice.heard(state.speaking, state.text)


def _ask_speaking(ctx: ServiceContext, own: OwnVoice) -> None:
    """Once, just after subscribing: is the robot in the middle of a sentence (the speech service's health)? Its
    `speaking=True` went out before this process listened. No answer (no speech service yet) is "not speaking"."""
    health = ctx.query_health("speech", timeout=SPEECH_ASK_S)
    speaking = health is not None and health.detail.get("speaking") is True
    own.assume(speaking)
    ctx.update_detail(own_voice_asked="no answer" if health is None else "speaking" if speaking else "silent")


def _engine_until_ready(ctx: ServiceContext, settings: VoiceSettings) -> Engine | None:
    """Build the engine; a missing model is reported as degraded health and retried."""
    while not ctx.stopping.is_set():
        try:
            engine = make_engine(settings.engine, vosk_model=settings.vosk_model, lexicon_path=settings.lexicon,
                                 head_path=settings.head or _enrolled_head(ctx), walk_gate=settings.walk_gate,
                                 agree_min=settings.agree_min, decoder=settings.decoder,
                                 stop_in_phrase=settings.stop_in_phrase, stop_in_long=settings.stop_in_long,
                                 warped_look=settings.warped_look, down_in_phrase=settings.down_in_phrase)
            head = getattr(engine, "head", None)  # the spotter: which speech embedding its head reads
            if head is not None:
                gate, phrase = getattr(engine, "gate", None), getattr(engine, "phrase_stop", None)
                ctx.update_detail(spotter_embedding=head.embedding,
                                  # int8 or float32: Whisper's arithmetic (`HRI_VOICE_WHISPER_COMPUTE`, `spotter.whisper`)
                                  spotter_compute=getattr(getattr(engine, "embedder", None), "compute_type", "float32"),
                                  spotter_walk_gate=gate.head.embedding if gate is not None else "none",
                                  spotter_agree_min=getattr(engine, "agree_min", 0.0),
                                  spotter_decoder=getattr(engine, "decoder", None) is not None,
                                  spotter_stop_in_phrase=phrase is not None,
                                  spotter_stop_in_long=getattr(engine, "long_stop", None) is not None,
                                  spotter_warped_look=getattr(engine, "warped_look", None) is not None,
                                  spotter_down_in_phrase=bool(getattr(phrase, "others", ())))
            ctx.log.info("engine ready", engine=engine.name, **({"embedding": head.embedding} if head else {}))
            return engine
        except EngineError as exc:
            ctx.set_status(HealthStatus.DEGRADED, engine_error=str(exc))
            ctx.log.error("engine unavailable", engine=settings.engine, error=str(exc))
            ctx.wait(max(settings.retry_s, 5.0))
    return None


def _enrolled_head(ctx: ServiceContext) -> str | None:
    """The enrolled head in the state folder if there is a usable one. An unreadable or corrupt one
    (a half-written file, another version's format) is not the user's fault to debug from a degraded
    service: the committed head is used instead, with a warning and `head_warning` in health."""
    from services.voice.enrol import enrolled_head_path
    from services.voice.spotter.head import Head, HeadError

    path = enrolled_head_path(ctx.keys.robot)
    if not path.is_file():
        return None
    try:
        Head.load(path)
    except HeadError as exc:
        warning = f"enrolled head unusable, using the committed head instead (re-run enroll): {exc}"
        ctx.log.warning("enrolled head unusable", path=str(path), error=str(exc), fallback="committed head")
        ctx.update_detail(head_warning=warning)
        return None
    return str(path)
