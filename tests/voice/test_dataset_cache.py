"""The training feature cache and its mel-spectrogram cache (`training/dataset.py`). Only noise clips are
rendered (no speech synthesiser needed); the embedding models must be installed."""

from __future__ import annotations

import numpy as np
import pytest

from services.voice.spotter.features import FRAMES, Embedder, FeatureError
from services.voice.training import dataset
from services.voice.training.dataset import OTHER, Recipe

try:
    Embedder()
except FeatureError as e:  # pragma: no cover - the spotter's dependencies are in the voice extra
    pytest.skip(str(e), allow_module_level=True)

ITEMS = [Recipe(kind, OTHER, seed=s) for kind, s in (("white", 1), ("pink", 2), ("hum", 3), ("brown", 4))]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HRI_VOICE_CACHE", str(tmp_path))
    return tmp_path


def test_features_are_the_service_embedding_and_the_mels_they_came_from_are_cached(cache, monkeypatch) -> None:
    x, y, idx = dataset.indexed_features(ITEMS, workers=1, progress=False)
    assert x.dtype == np.float16 and x.shape[1:] == (FRAMES, 96) and len(idx) >= 2
    emb = Embedder()
    for row, i in enumerate(idx):  # unchanged: exactly what the service computes for the rendered clip
        expected = emb.utterance(dataset.render(ITEMS[i]), seed=ITEMS[i].seed).astype(np.float16)
        np.testing.assert_array_equal(x[row], expected)
    assert len(list(cache.glob("spotter-mels-*.npz"))) == 1

    def no_render(*_a, **_k):
        raise AssertionError("rendered although cached")

    monkeypatch.setattr(dataset, "_render_all", no_render)
    mel, y2, idx2 = dataset.indexed_mels(ITEMS, workers=1, progress=False)
    x2, _, _ = dataset.indexed_features(ITEMS, workers=1, progress=False)
    np.testing.assert_array_equal(x2, x)
    np.testing.assert_array_equal(idx2, idx)
    np.testing.assert_array_equal(y2, y)
    assert mel.dtype == np.float16 and mel.shape[0] == len(idx) and mel.shape[2] == 32
    # the cached (float16) spectrograms embed back to the cached features, up to float16 rounding ...
    back = np.stack([emb.embed_mel(m.astype(np.float32))[:FRAMES] for m in mel])
    rounding = np.abs(back - x.astype(np.float32)).max()
    assert rounding < 0.02 * np.abs(x.astype(np.float32)).max()
    # ... and a change made at the mel level reaches the embedding, far beyond that rounding
    louder = np.stack([emb.embed_mel(m.astype(np.float32) + 1.0)[:FRAMES] for m in mel])
    assert np.abs(louder - back).max() > max(1.0, 20 * rounding)


def test_features_cached_without_mels_are_rendered_once_more_and_kept(cache) -> None:
    _, _, idx = dataset.indexed_features(ITEMS[:2], workers=1, progress=False)
    (mel_file,) = cache.glob("spotter-mels-*.npz")
    (feature_file,) = cache.glob("spotter-features-*.npz")
    mel_file.unlink()
    before = feature_file.stat().st_mtime_ns
    mel, _, idx2 = dataset.indexed_mels(ITEMS[:2], workers=1, progress=False)
    assert mel_file.exists() and feature_file.stat().st_mtime_ns == before
    assert mel.shape[0] == len(idx)
    np.testing.assert_array_equal(idx2, idx)
