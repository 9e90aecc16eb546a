"""Which speech embedding a head reads: a head records the one it was trained on (`Head.embedding`).

- `speech-embedding`: Google's speech-embedding model from the openwakeword 0.4.0 wheel (`features`);
  (16, 96) per utterance. Heads that record no embedding were trained on it.
- `whisper-tiny.en`: the encoder of Whisper tiny.en, run by CTranslate2 (`whisper`); (10, 384), 200 ms averages.
- `whisper-tiny.en-100ms`: the same encoder's output in 100 ms averages; (20, 384) (round voice21).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from services.voice.spotter import whisper
from services.voice.spotter.features import EMBED_DIM, FRAMES, Embedder, FeatureError

SPEECH_EMBEDDING = "speech-embedding"
EMBEDDINGS = (SPEECH_EMBEDDING, whisper.NAME, whisper.FINE_NAME)
SHAPES = {SPEECH_EMBEDDING: (FRAMES, EMBED_DIM), whisper.NAME: (whisper.FRAMES, whisper.DIM),
          whisper.FINE_NAME: (whisper.FINE_FRAMES, whisper.DIM)}
"""What each embedding gives per utterance."""


class UtteranceEmbedder(Protocol):
    def utterance(self, pcm: bytes, seed: int = 0) -> np.ndarray:
        """One trimmed utterance (16-bit PCM) -> its fixed-size embedding."""
        ...


def embedder_for(name: str, threads: int = 1) -> UtteranceEmbedder:
    """The embedder a head trained on `name` needs (FeatureError if it is unknown or cannot load)."""
    if name == SPEECH_EMBEDDING:
        return Embedder(threads=threads)
    if name in (whisper.NAME, whisper.FINE_NAME):  # one encoder, pooled into the frames SHAPES gives the name
        return whisper.WhisperEmbedder(threads=threads, frames=SHAPES[name][0])
    raise FeatureError(f"unknown speech embedding {name!r}: one of {', '.join(EMBEDDINGS)}")
