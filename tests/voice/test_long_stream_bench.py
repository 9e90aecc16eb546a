"""`bench/voice_long_stream.py`: words placed where it says in one stream, and counted as the service hears them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bench.voice_bench import OTHER, WORDS, Item, Policy, _rendered
from bench.voice_long_stream import disagreement, heard, long_stream, way_config
from services.voice import synth
from services.voice.audio import SAMPLE_RATE, read_wav
from services.voice.engine import make_engine
from services.voice.segmenter import SegmenterConfig
from services.voice.training import dataset


def _item(word: str, label: int) -> Item:
    return Item("espeak", "en-us", label, word, "clean", read_wav(synth.speech_clip(word, "en", 130).path))


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_words_are_placed_at_their_level_and_heard_with_their_latency() -> None:
    items = [_item("stop", WORDS.index("stop")), _item("banana", OTHER), _item("yes", WORDS.index("yes"))]
    pcm, placed = long_stream(items, -20.0, -70.0, 3.0, seed=4)
    x = np.frombuffer(pcm, "<i2") / 32768.0
    assert len(placed) == 3 and all(a.end_s < b.start_s for a, b in zip(placed, placed[1:], strict=False))
    for p in placed:  # each word where it says, at its level; the pause before it is the room's hiss
        word = x[int(p.start_s * SAMPLE_RATE) : int(p.end_s * SAMPLE_RATE)]
        assert 20 * np.log10(np.abs(word).max()) == pytest.approx(-20.0, abs=0.5)
        before = x[int((p.start_s - 0.9) * SAMPLE_RATE) : int((p.start_s - 0.1) * SAMPLE_RATE)]
        assert 10 * np.log10(np.mean(before**2)) == pytest.approx(-70.0, abs=1.5)
    row = heard(make_engine("spotter"), pcm, placed, SegmenterConfig(), Policy())
    assert row["commands"] == 2 and row["others"] == 1 and row["heard"] == 2 and row["false_walks"] == 0
    assert row["heard_at"] == [0, 2]  # word by word: which of the stream's words were heard
    assert 0.0 < row["latency_p50_ms"] < 600.0  # type: ignore[operator]


@pytest.mark.parametrize(("way", "reset", "fresh", "bar"), [("off", None, None, None), ("1", 1.0, None, None),
                                                            ("fresh2", None, 2.0, None), ("freshoff", None, None, None),
                                                            ("fresh1:30", None, 1.0, 30.0),
                                                            ("default", SegmenterConfig.vad_reset_s,
                                                             SegmenterConfig.vad_fresh_end_s,
                                                             SegmenterConfig.vad_fresh_end_snr_db)])
def test_each_way_names_one_setting_and_leaves_the_other_off(way: str, reset: float | None, fresh: float | None,
                                                             bar: float | None) -> None:
    config = way_config(way)
    assert (config.vad_reset_s, config.vad_fresh_end_s, config.vad_fresh_end_snr_db) == (reset, fresh, bar)


@pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")
def test_a_tuning_set_is_cached_under_its_own_name_never_as_held_out(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HRI_VOICE_CACHE", str(tmp_path))
    jobs = [(dataset.Recipe("stop", WORDS.index("stop"), "espeak:en-us+m2", 1.0, 1.0, 5, 0.0), "clean")]
    items = _rendered(jobs, workers=1, required=False, split="tuning")
    assert [it.text for it in items] == ["stop"] and len(items[0].pcm) > SAMPLE_RATE // 5
    assert [p.name.split("-")[1] for p in tmp_path.glob("bench-*.pickle")] == ["tuning"]
    assert _rendered(jobs, workers=1, required=False, split="tuning")[0].pcm == items[0].pcm  # read back from it


def test_ways_are_compared_word_by_word_with_the_first() -> None:
    base = {"heard_at": [0, 2, 5, 7], "accepted_at": [1, 4]}
    row = {"heard_at": [0, 5, 7, 8, 9], "accepted_at": [4, 6, 10]}
    assert disagreement(base, row) == {"commands_lost": 1, "commands_gained": 2, "others_newly_taken": 2,
                                       "others_no_longer_taken": 1}
    assert disagreement(base, base) == dict.fromkeys(disagreement(base, base), 0)
