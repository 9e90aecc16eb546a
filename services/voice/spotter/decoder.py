"""A second opinion from Whisper tiny.en's decoder: the first word it would write for the utterance.

The default head reads Whisper's encoder (`whisper.py`) and was trained on synthetic voices only. The decoder
beside that encoder was trained, with it, on 680,000 hours of people's speech and has never been fitted to
anything of ours, so where the head has not heard a kind of voice the decoder still may (round voice30).

`FirstWord.of(frames)` runs the decoder on the encoder output the head's embedding is pooled from (the
utterance's unpadded 2 s window: 100 frames, so it costs one short decoding, ~20-25 ms on one core, and no second
encoding) for two steps, greedily, after `<|startoftranscript|><|notimestamps|>`:

- `first[c]`: the probability that the first token is command c (" Go", " go" or "Go": every single-token
  spelling of the word, `spellings`);
- `ends`: when that greedy first token is a command's, the probability that the next token ends the word:
  a full stop, "!", "?", ",", the end of the text, or the same word again (on a 2 s window the decoder, made for
  30 s, often repeats a word: "Stand Stand Stand"), not its continuation ("Go" + "at" is goat).

How the engine uses it (`SpotterEngine`, `HRI_VOICE_DECODER=on`): only where the head accepts no command (it
hears "other", or a command below its accept knot), the utterance is *rescued* as command c if the greedy first
token is c's with `first[c]` >= `RESCUE_AT` (0.5) and `ends` >= `ENDS_AT` (0.6). It is published with a confidence from 0.5
up to `RESCUE_CONFIDENCE`: enough for the reasoner to act on (0.5), too little for a "go" to walk unasked (0.85:
the robot asks) or for a "yes" to confirm a question (0.7). The decoder alone never makes the robot walk, and a
command the head accepts is never changed, so the decoder costs no time where the head hears a command.

Why no veto the other way (a command the head accepts, dropped where the decoder would not write it): on the
tuning voices it cost more commands than other words (the decoder hears espeak-ng's voices badly: espeak-ng en-gb
f3 42 -> 31 of 42 commands). The thresholds were chosen on tuning voices only (Kokoro's jf_alpha, jf_gongitsune,
jf_tebukuro and Festival's British rab and don, none in a training split of the committed head or in a bench row;
voice README, rounds 30 and 30b: with 0.3 instead of 0.5 the decoder heard 15 more of 504 held-out commands but
took 31 more of 1,914 held-out other words, twice what those tuning draws had shown; 0.5 is where the head's own
tune splits (1,600 clips) show about one other word per three commands rescued). Off by default: at 0.5, on two
fresh seeds, it heard 10 more of 504 held-out commands and 9 more of the neural voices' 126, never walked, and took
8 and 14 more of 1,914 other words, with 6 and 12 more unasked questions; the second seed was past its rule's bars.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

RESCUE_AT = 0.5
"""A command the head does not accept is heard if the decoder's first token is that word with at least this..."""
ENDS_AT = 0.6
"""... and the word ends there with at least this probability."""
RESCUE_CONFIDENCE = 0.6
"""The highest confidence a rescued command is published with (0.5 + 0.1 x the decoder's probability)."""
END_MARKS = (".", "!", "?", ",")


def _log_softmax(x: np.ndarray) -> np.ndarray:
    m = float(x.max())
    return x - (m + np.log(np.exp(x - m).sum()))


def _mass(logp: np.ndarray, ids: list[int]) -> float:
    return float(np.exp(logp[ids]).sum()) if ids else 0.0


@dataclass(frozen=True)
class Opinion:
    """The decoder's reading of one utterance (`FirstWord.of`)."""

    first: dict[str, float]
    """per command, the probability that the first token is that word"""
    best: str | None
    """the command whose spelling the greedy first token is, or None"""
    ends: float
    """with `best`: the probability that the word ends after that token (0.0 without)"""

    def rescue(self) -> tuple[str, float] | None:
        """The command the decoder hears where the head heard none, with its published confidence; or None."""
        if self.best is None or self.first[self.best] < RESCUE_AT or self.ends < ENDS_AT:
            return None
        return self.best, 0.5 + (RESCUE_CONFIDENCE - 0.5) * self.first[self.best]


class FirstWord:
    """Whisper's decoder over the encoder output of `model` (the CTranslate2 Whisper the embedder loaded), for
    the words of `vocabulary`; `tokenizer_path`: the model folder's `tokenizer.json`."""

    def __init__(self, model: Any, tokenizer_path: str, vocabulary: tuple[str, ...]) -> None:
        from tokenizers import Tokenizer

        try:
            tok = Tokenizer.from_file(tokenizer_path)
        except Exception as exc:  # the tokenizers library's own error types: a missing or unreadable file
            raise ValueError(f"{tokenizer_path}: the Whisper model's tokenizer cannot be read ({exc}); the decoder's "
                             f"opinion needs the model folder's tokenizer.json") from None
        self._model = model
        self._prompt = [tok.token_to_id("<|startoftranscript|>"), tok.token_to_id("<|notimestamps|>")]
        if None in self._prompt:
            raise ValueError(f"{tokenizer_path}: not a Whisper tokenizer (no start-of-transcript tokens)")
        self.vocabulary = vocabulary
        self.spellings = {w: spellings(tok, w) for w in vocabulary}
        """per command, the ids of its single-token spellings"""
        ends = [t for mark in END_MARKS for t in tok.encode(mark, add_special_tokens=False).ids]
        self._ends = sorted(set(ends) | {tok.token_to_id("<|endoftext|>")})
        self._owner = {t: w for w, ids in self.spellings.items() for t in ids}

    def of(self, frames: np.ndarray) -> Opinion:
        """The decoder's opinion of one utterance from its encoder output `frames` (time, width)."""
        import ctranslate2

        view = ctranslate2.StorageView.from_array(np.ascontiguousarray(frames[None], dtype=np.float32))
        result = self._model.generate(view, [self._prompt], max_length=len(self._prompt) + 2, beam_size=1,
                                      return_logits_vocab=True, suppress_blank=False, suppress_tokens=[])[0]
        steps = np.asarray(result.logits[0], dtype=np.float32)
        logp = _log_softmax(steps[0])
        first = {w: _mass(logp, ids) for w, ids in self.spellings.items()}
        tokens = result.sequences_ids[0]
        best = self._owner.get(tokens[0]) if tokens else None
        ends = 0.0
        if best is not None and len(steps) > 1:
            ends = _mass(_log_softmax(steps[1]), self._ends + self.spellings[best])
        return Opinion(first, best, ends)


def spellings(tok: Any, word: str) -> list[int]:
    """The ids of every spelling of `word` that Whisper's tokenizer writes as one token: " Go", " go", "Go",
    " GO" (a spelling that takes two tokens is left out: its first token is another word's too)."""
    forms = (" " + word.capitalize(), " " + word, word.capitalize(), " " + word.upper())
    ids = {t[0] for f in forms if len(t := tok.encode(f, add_special_tokens=False).ids) == 1}
    return sorted(ids)
