"""Free-form recognition of a WAV with pocketsphinx's bundled US English model and language model.

Not the voice service's command grammar: any English words can come out, so this shows which
words were actually said.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pocketsphinx import Decoder
from scipy.signal import resample_poly

from services.speech.audio import read_samples

RATE = 16000


def make_decoder() -> Decoder:
    return Decoder(samprate=RATE, loglevel="FATAL")


def transcribe(decoder: Decoder, wav: Path) -> list[str]:
    samples, rate = read_samples(wav)
    pcm = resample_poly(samples, RATE, rate) * 32767.0
    pad = np.zeros(RATE // 5)  # 200 ms lead-in and tail
    pcm = np.concatenate([pad, pcm, pad])
    pcm += np.random.default_rng(0).normal(0.0, 2.0, len(pcm))  # dither: exact-zero silence hurts decoding
    data = np.clip(pcm, -32768, 32767).astype(np.int16).tobytes()
    decoder.start_utt()
    decoder.process_raw(data, full_utt=True)
    decoder.end_utt()
    hyp = decoder.hyp()
    return hyp.hypstr.split() if hyp is not None else []
