"""bench/voice_proxy.py: the left-out speaker is out of training and calibration, and its clips are scored as its own.

Tiny synthetic feature rows (not the feature cache): each row's first value is its row number, so the rows a
fit or a calibration received can be read back."""

from __future__ import annotations

import importlib.util
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from services.voice.spotter.features import EMBED_DIM, FRAMES
from services.voice.spotter.head import Head
from services.voice.training import corpus, train
from services.voice.training.train import TrainConfig

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("voice_proxy", ROOT / "bench" / "voice_proxy.py")
assert _spec is not None and _spec.loader is not None
vp = importlib.util.module_from_spec(_spec)
sys.modules["voice_proxy"] = vp
_spec.loader.exec_module(vp)

N = len(corpus.VOCABULARY)
D = "flite:awb"
VOICES = ("flite:awb", "flite:awb@vtl1.105", "flite:kal16", "flite:kal16@vtl0.9", "festival:ked", "espeak:en-us+m1")
SMALL = replace(TrainConfig(), hidden=4)


def rows(n: int, splits: tuple[str, ...], seed: int = 0) -> vp.Rows:
    """n rows, every class and every voice in each split; x[i, 0, 0] = i (exact in float16 below 2048)."""
    rng = np.random.default_rng(seed)
    y = np.arange(n) % (N + 1)
    x = (rng.normal(size=(n, FRAMES, EMBED_DIM)) + 0.5 * y[:, None, None]).astype(np.float16)
    x[:, 0, 0] = np.arange(n)
    voice = np.array([VOICES[(i // (N + 1)) % len(VOICES)] for i in range(n)])
    split = np.array([splits[i % len(splits)] for i in range(n)])
    text = np.array([corpus.VOCABULARY[c] if c < N else "table" for c in y])
    return vp.Rows(x, y, voice, split, text)


def ids(x: np.ndarray) -> set[int]:
    return {int(v) for v in np.asarray(x)[:, 0, 0]}


def by_d(r: vp.Rows) -> set[int]:
    return {i for i, v in enumerate(r.voice) if v == D or v.startswith(D + "@vtl")}


def test_the_left_out_speaker_and_its_virtual_speakers_are_not_fitted_on(monkeypatch: pytest.MonkeyPatch,
                                                                           tmp_path: Path) -> None:
    data = rows(288, ("train", "speakers"))
    seen: list[set[int]] = []
    real = train.crop_rows
    monkeypatch.setattr(train, "crop_rows", lambda x, y, cfg: (seen.append(ids(x)), real(x, y, cfg))[1])
    head, info = vp.fitted_head(data, D, [12], SMALL, tmp_path)
    assert seen and by_d(data) and not seen[0] & by_d(data)  # neither flite:awb nor flite:awb@vtl...
    assert seen[0] == set(range(len(data.y))) - by_d(data)  # every other row (kal16's warps too)
    assert info["train_rows"] == len(data.y) - len(by_d(data))
    # The member is kept and read back as it was; a cache fitted on other rows is refused.
    again, info2 = vp.fitted_head(data, D, [12], SMALL, tmp_path)
    assert info2["members"][12]["cached"] and not info["members"][12]["cached"]
    assert all(np.array_equal(a, b) for a, b in zip(head.weights, again.weights, strict=True))
    with pytest.raises(Exception, match="another recipe or other data"):
        vp.fitted_head(rows(288, ("train", "speakers"), seed=1), D, [12], SMALL, tmp_path)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # tune_figures' "go" rates on a half without "go"s: nan
def test_the_left_out_speaker_is_not_calibrated_on(monkeypatch: pytest.MonkeyPatch) -> None:
    tune = rows(240, train.TUNE_SPLITS)
    head, _ = vp.fitted_head(rows(288, ("train",), seed=2), D, [12], SMALL, None)
    seen: list[set[int]] = []
    real = train.calibrate
    monkeypatch.setattr(train, "calibrate", lambda h, x, y, cfg: (seen.append(ids(x)), real(h, x, y, cfg))[1])
    figures = vp.plain(head, tune, D, SMALL)
    assert len(seen) == 2 and not (seen[0] | seen[1]) & by_d(tune)
    assert seen[0] | seen[1] == set(range(len(tune.y))) - by_d(tune)  # the two halves: every other tune row
    assert not seen[0] & seen[1]
    assert set(figures) == {"left_out", "tune"}
    cal = vp.calibration_rows(tune, D, SMALL)  # the enrolment proxy's calibration: train's splits, without d
    assert not ids(tune.x[cal]) & by_d(tune)
    assert set(tune.split[cal]) == set(SMALL.tune_splits) and "recorded-tune" not in set(tune.split[cal])


def test_the_left_out_speakers_clips_are_what_is_scored() -> None:
    tune = rows(240, train.TUNE_SPLITS)
    m = vp.left_out(tune, D)
    assert m.any() and set(tune.voice[m]) == {D} and set(tune.split[m]) == {"recorded-tune"}


def test_a_left_out_speakers_non_command_published_counts_as_accepted() -> None:
    """A head that says "go" for a clip whose first value is positive, "other" otherwise."""
    go = corpus.VOCABULARY.index("go")
    dim = 8 * EMBED_DIM
    w0 = np.zeros((dim, 1), np.float32)
    w0[0, 0] = 1.0
    w1 = np.zeros((1, N + 1), np.float32)
    w1[0, go] = 40.0
    b1 = np.zeros(N + 1, np.float32)
    b1[N] = 20.0
    head = Head(corpus.VOCABULARY, np.zeros(dim, np.float32), np.ones(dim, np.float32), [w0, w1],
                [np.zeros(1, np.float32), b1], np.full(N, 0.5), np.full(N, 0.9), crop_width=8, crop_starts=(0,))
    x = np.zeros((4, FRAMES, EMBED_DIM), np.float32)
    x[:2, 0, 0] = 1.0  # rows 0, 1: heard as a sure "go"
    y = np.array([N, go, N, go])  # row 0 a non-command accepted as "go"; row 3 a "go" missed
    policy = type("P", (), {"min_confidence": 0.5, "confirm_below": 0.85})()
    f = vp.enrol_figures(head, x, y, policy)
    assert (f["n_other_accepted"], f["n_other"], f["other_accepted"]) == (1, 2, 0.5)
    assert f["command_accuracy"] == 0.5
    assert (f["false_go_walk"], f["false_go_ask"]) == (1, 0)


def test_foreign_voices_are_fitted_on_in_every_rotation_and_never_scored() -> None:
    """Round 11's `--foreign`: the foreign split's rows stay in every rotation's training rows."""
    data = rows(96, ("train",))
    data.voice[:16] = "foreign:cs_dita"
    data.split[:16] = "foreign"
    for d in vp.SPEAKERS.values():
        keep = vp.without(data, d)
        assert keep[:16].all() and not (keep & (data.speakers() == d)).any()
        assert not vp.left_out(data, d)[:16].any()
