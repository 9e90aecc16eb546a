"""The pieces without a bus: text checks, the bounded queue with its staleness cap, configuration."""

from __future__ import annotations

from pathlib import Path

import pytest

from services.runtime import ConfigError
from services.speech.config import OutputTarget, SpeechConfig, default_folder, parse_output
from services.speech.player import file_stem
from services.speech.queue import SpeechQueue, Utterance
from services.speech.text import TextRejected, clean_text


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


# ---------------------------------------------------------------- text
def test_text_is_cleaned_to_one_line() -> None:
    assert clean_text("  Sorry,\n\tI cannot\x00do it.  ", 400) == "Sorry, I cannot do it."


@pytest.mark.parametrize(
    ("raw", "reason"),
    [
        ("", "empty"),
        (" \n\t ", "empty"),
        ("\x00\x07", "empty"),
        ("...!?", "no letters"),
        ("a" * 401, "too long"),
    ],
)
def test_bad_text_is_rejected_with_a_reason(raw: str, reason: str) -> None:
    with pytest.raises(TextRejected, match=reason):
        clean_text(raw, 400)


# ---------------------------------------------------------------- queue
def test_queue_keeps_order() -> None:
    q = SpeechQueue(4, 5.0)
    for i in range(3):
        assert q.put(Utterance(f"u{i}", "x")) is None
    assert [q.take(0)[0].id for _ in range(3)] == ["u0", "u1", "u2"]  # type: ignore[union-attr]
    assert q.take(0.01) == (None, [])


def test_full_queue_drops_the_oldest_and_counts() -> None:
    q = SpeechQueue(2, 5.0)
    q.put(Utterance("a", "x"))
    q.put(Utterance("b", "x"))
    dropped = q.put(Utterance("c", "x"))
    assert dropped is not None and dropped.utterance.id == "a" and dropped.reason == "queue_full"
    assert q.put(Utterance("d", "x")).utterance.id == "b"  # type: ignore[union-attr]
    assert q.dropped_full == 2 and len(q) == 2
    assert [q.take(0)[0].id for _ in range(2)] == ["c", "d"]  # type: ignore[union-attr]


def test_stale_requests_are_skipped_when_their_turn_comes() -> None:
    clock = FakeClock()
    q = SpeechQueue(8, 2.0, clock=clock)
    q.put(Utterance("old1", "x", received=clock.now))
    q.put(Utterance("old2", "x", received=clock.now + 0.5))
    q.put(Utterance("fresh", "x", received=clock.now + 2.0))
    clock.now += 3.0  # old1 waited 3 s, old2 2.5 s, fresh 1 s
    item, skipped = q.take(0)
    assert item is not None and item.id == "fresh"
    assert [(s.utterance.id, s.reason) for s in skipped] == [("old1", "stale"), ("old2", "stale")]
    assert skipped[0].age_s == pytest.approx(3.0)
    assert q.dropped_stale == 2


def test_take_waits_for_a_put() -> None:
    import threading

    q = SpeechQueue(2, 5.0)
    threading.Timer(0.05, lambda: q.put(Utterance("late", "x"))).start()
    item, _ = q.take(2.0)
    assert item is not None and item.id == "late"


# ---------------------------------------------------------------- config and file names
def test_output_parsing(tmp_path: Path) -> None:
    assert parse_output(None) is None and parse_output("  ") is None
    assert parse_output("device") == OutputTarget(device="")
    assert parse_output("device:plughw:1") == OutputTarget(device="plughw:1")
    assert parse_output(str(tmp_path)) == OutputTarget(folder=tmp_path)
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match="not a folder"):
        parse_output(str(tmp_path / "file"))
    with pytest.raises(ConfigError, match="ALSA PCM"):
        parse_output("device:")


def test_default_folder_follows_xdg_state_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path))
    assert default_folder("op2") == tmp_path / "hri" / "op2" / "speech"
    assert SpeechConfig().output_for("r1") == OutputTarget(folder=tmp_path / "hri" / "r1" / "speech")
    monkeypatch.delenv("XDG_STATE_HOME")
    assert default_folder("op2") == Path.home() / ".local" / "state" / "hri" / "op2" / "speech"
    monkeypatch.setenv("HRI_STATE_DIR", str(tmp_path / "state"))  # the robot's state folder wins
    assert default_folder("op2") == tmp_path / "state" / "speech"


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"rate": 20}, "rate"), ({"volume": 300}, "volume"), ({"voice": "en us"}, "voice"),
     ({"queue_size": 0}, "queue"), ({"max_age_s": 0}, "max age"), ({"max_chars": 0}, "max chars")],
)
def test_bad_settings_are_clear_errors(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        SpeechConfig(**kwargs)  # type: ignore[arg-type]


def test_ids_become_safe_file_names() -> None:
    assert file_stem("reply-1.a_b") == "reply-1.a_b"
    assert file_stem("../../etc/passwd") == "_._.._etc_passwd"
    assert "/" not in file_stem("a/b") and not file_stem(".hidden").startswith(".")
    assert len(file_stem("x" * 500)) == 120
