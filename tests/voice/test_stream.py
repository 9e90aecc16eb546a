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
    assert all(u.origin.startswith("stdin@") for u in found)


def test_pure_noise_stream_yields_nothing_long() -> None:
    noise = synth.noise_clip("pink", -45.0, seconds=4.0)
    pcm = noise.path.read_bytes()[44:]
    step = 960
    found = list(stream_utterances((pcm[i : i + step] for i in range(0, len(pcm), step)), "noise"))
    assert len(found) <= 1
