"""bench/voice_bench.py's rows of `corpus.HELDOUT_EXTRA`: adding the neural voices left every earlier voice's clips as
they were (so their rows compare with earlier runs), and a neural voice's words come at several speeds; and the stream
benches' rows compared word for word (`voice_walking.paired`)."""

from __future__ import annotations

import pytest

from bench import voice_bench
from services.voice.training import corpus


def test_the_neural_voices_come_last_and_leave_the_earlier_voices_clips_unchanged(monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("pocketsphinx")  # the CMU dictionary (forbidden negatives) ships in its wheel
    now = voice_bench.extra_recipes(3636)
    earlier = corpus.HELDOUT_EXTRA[: -len(corpus.HELDOUT_NEURAL)]
    assert corpus.HELDOUT_EXTRA[len(earlier):] == corpus.HELDOUT_NEURAL
    monkeypatch.setattr(corpus, "HELDOUT_EXTRA", earlier)
    before = voice_bench.extra_recipes(3636)
    assert now[: len(before)] == before and all(r.speed == 1.0 for r, _ in before)
    neural = now[len(before):]
    assert {r.voice for r, _ in neural} == set(corpus.HELDOUT_NEURAL)
    per_voice = len(neural) // len(corpus.HELDOUT_NEURAL)
    assert per_voice == len(before) // len(earlier) * len(voice_bench.NEURAL_CONDITIONS) // len(voice_bench.EXTRA_CONDITIONS)
    assert {r.speed for r, _ in neural} == {0.85, 1.0, 1.15}


def test_paired_counts_the_words_each_run_counted_and_the_other_did_not() -> None:
    from bench.voice_walking import paired

    assert paired("1100", "1010") == (1, 1)
    assert paired("111", "111") == (0, 0)
    with pytest.raises(ValueError, match="not the same clips"):
        paired("10", "100")


def test_the_bench_counts_a_go_walked_at_once_apart_from_one_asked_and_confirmed() -> None:
    from schemas.messages import Command
    from services.voice.engine import Recognition

    heard = {b"walk": (Command.GO, 0.9), b"ask": (Command.GO, 0.7), b"ask-unconfirmed": (Command.GO, 0.7),
             b"yes": (Command.YES, 0.8), b"yes-unsure": (Command.YES, 0.6), b"gold": (Command.GO, 0.6)}

    class Fixed:
        name = "fixed"

        def recognise(self, pcm: bytes) -> Recognition:
            command, conf = heard[pcm]
            return Recognition(command, command.value, conf, self.name)

    go, yes = voice_bench.WORDS.index("go"), voice_bench.WORDS.index("yes")
    items = [voice_bench.Item("espeak-heldout", "a", go, "go", "clean", b"walk"),
             voice_bench.Item("espeak-heldout", "a", go, "go", "noisy", b"ask"),
             voice_bench.Item("espeak-heldout", "a", yes, "yes", "noisy", b"yes"),
             voice_bench.Item("espeak-heldout", "b", go, "go", "clean", b"ask-unconfirmed"),
             voice_bench.Item("espeak-heldout", "b", yes, "yes", "clean", b"yes-unsure"),
             voice_bench.Item("espeak-heldout", "b", voice_bench.OTHER, "gold", "clean", b"gold")]
    scores, _ = voice_bench.score("fixed", Fixed(), items, voice_bench.Policy())
    row = next(s for s in scores if s.family == "ALL").row()
    assert row["go_walked"] == 1  # the sure "go"; the asked ones are not walks
    assert row["go_asked"] == 2 and row["of_which_asked_and_confirmed"] == 1  # b's "yes" is below 0.7
    assert row["false_asks"] == 1 and row["false_walks_direct"] == 0  # "gold" heard as "go" at 0.6: asked
