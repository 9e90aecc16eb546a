"""The stream path: VAD finds the utterances of a long recording with silence and noise between them."""

from __future__ import annotations

import io

import pytest

from services.voice import synth
from services.voice.audio import SAMPLE_RATE, SAMPLE_WIDTH
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.sources import SourceSpec, stream_utterances, utterances

pytestmark = pytest.mark.skipif(not synth.espeak_available(), reason="espeak-ng not installed")

WORDS = ["stand", "table", "stop", "yes"]


@pytest.fixture(scope="module")
def recording() -> tuple[bytes, list[float]]:
    clips = [synth.speech_clip(w, "en-us", 150) for w in WORDS]
    pcm = synth.recording(clips, gap_s=1.2, noise_dbfs=-45.0)
    # expected speech centres: each gap then each clip (whose speech is padded by PAD_S)
    centres, t = [], 0.0
    for clip in clips:
        t += 1.2
        n = clip.path.stat().st_size - 44
        dur = n / (SAMPLE_RATE * SAMPLE_WIDTH)
        centres.append(t + dur / 2)
        t += dur
    return pcm, centres


@pytest.mark.parametrize("vad", ["silero", "webrtc"])
def test_segmenter_finds_each_utterance(recording: tuple[bytes, list[float]], vad: str) -> None:
    pcm, centres = recording
    seg = Segmenter(SegmenterConfig(vad=vad))
    step = 4800  # 150 ms chunks, not a multiple of the VAD frame
    found = [s for i in range(0, len(pcm), step) for s in seg.feed(pcm[i : i + step])] + seg.flush()
    assert len(found) == len(WORDS), [(s.start_s, s.end_s) for s in found]
    for s, centre in zip(found, centres, strict=True):
        assert s.start_s <= centre <= s.end_s
        assert s.end_s - s.start_s < 2.0


def test_stdin_source_yields_utterances(recording: tuple[bytes, list[float]]) -> None:
    pcm, _ = recording
    found = list(utterances(SourceSpec("stdin"), lambda: False, stdin=io.BytesIO(pcm)))
    assert len(found) == len(WORDS)
    assert all(u.origin == f"stdin@{u.start_s:.2f}s" for u in found)  # where each starts, also as a number
    assert [u.start_s for u in found] == sorted(u.start_s for u in found)


def test_pure_noise_stream_yields_nothing_long() -> None:
    noise = synth.noise_clip("pink", -45.0, seconds=4.0)
    pcm = noise.path.read_bytes()[44:]
    step = 960
    found = list(stream_utterances((pcm[i : i + step] for i in range(0, len(pcm), step)), "noise"))
    assert len(found) <= 1


def test_speech_longer_than_the_longest_utterance_is_cut_into_consecutive_parts() -> None:
    """A person reading on: the segmenter cuts the speech every `max_utterance_s`, and each part is the audio that
    follows the one before (it used to start where the whole speech started: the same audio again, then none at all
    once that had left the history, and pocketsphinx raised on the empty utterance)."""
    from tests.voice.streams import STEP, word_stream

    pcm = word_stream(*["stand", "table", "window", "music", "morning", "yesterday"] * 2, gap_s=0.0)
    config = SegmenterConfig(max_utterance_s=1.0)
    seg = Segmenter(config)
    found = [s for i in range(0, len(pcm), STEP) for s in seg.feed(pcm[i : i + STEP])] + seg.flush()
    assert len(found) >= 4, [(s.start_s, s.end_s) for s in found]
    rolls = config.pre_roll_s + config.post_roll_s
    for before, after in zip(found, found[1:], strict=False):
        assert after.start_s > before.start_s
        assert after.start_s >= before.end_s - rolls - 0.01  # no audio handed over twice, beyond the rolls
    for s in found:
        assert len(s.pcm) == round((s.end_s - s.start_s) * SAMPLE_RATE) * SAMPLE_WIDTH > 0
