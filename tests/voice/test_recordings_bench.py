"""bench/voice_recordings.py: what a transcript says, how published commands are scored, and the service's path on
the recordings of three wheels (a person reading; a neural TTS dialogue; two people on a telephone line; a voice
saying Beckett)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bench.voice_bench import Policy
from bench.voice_recordings import (
    ENDGAME,
    RECORDINGS_DIR,
    WHEEL_RECORDINGS,
    Recording,
    said,
    score,
    score_words,
    stm_lines,
    stream,
    wheel_recordings,
    word_clips,
)
from schemas.messages import Command
from services.voice.segmenter import SegmenterConfig

REC = Recording("x.wav", "test", np.zeros(16000), ENDGAME)


def _need(*names: str) -> None:
    """Skip, saying how to fetch them, unless the wheels holding these recordings are downloaded."""
    missing = {w.requirement for w in WHEEL_RECORDINGS if Path(w.path).name in names and w.wheel(RECORDINGS_DIR) is None}
    if missing:
        pytest.skip(f"not downloaded ({' '.join(sorted(missing))}): ./run setup puts them in {RECORDINGS_DIR}")


def test_a_command_word_alone_on_its_line_is_expected_and_inside_a_sentence_only_mentioned() -> None:
    expected, mentioned = said(ENDGAME)
    assert expected == {"yes": 2, "no": 1}
    assert mentioned == {"yes": 2, "no": 2}  # "No, not heartily, just less heartily."; "Not now." is no "no"


def test_an_stm_transcript_gives_each_segments_words() -> None:
    stm = ";; a comment\nsample 1 Diane 6.68 7.16 Hello?\nsample 1 Sheila 24.058 28.425 At least you know, down here\n"
    assert stm_lines(stm) == ("Hello?", "At least you know, down here")
    assert said(stm_lines(stm)) == ({}, {"down": 1})  # a command word inside a line is mentioned, not expected


def test_published_commands_are_matched_to_what_was_said() -> None:
    policy = Policy()
    heard = [(0.0, Command.YES, 0.9, "yes"), (1.0, Command.NO, 0.7, "no"), (2.0, Command.NO, 0.6, "no"),
             (3.0, Command.STOP, 0.8, "stop"), (4.0, Command.GO, 0.6, "go"), (5.0, Command.DOWN, 0.4, "down")]
    row = score(heard, REC, policy)
    assert row["heard"] == 2  # one yes, one no alone; the second "no" is the mentioned one
    assert row["false"] == {"stop": 1, "go": 1}  # "down" at 0.4 is below what the reasoner acts on
    assert (row["false_walks"], row["false_asks"]) == (0, 1)
    walk = score([(0.0, Command.GO, 0.9, "go")], REC, policy)
    assert (walk["false_walks"], walk["false_asks"]) == (1, 0)


@pytest.mark.parametrize("decoder", ["off", "on"])  # on: Whisper's decoder may rescue what the head missed (round 30)
def test_the_service_path_hears_the_dialogues_yes_and_no_and_no_command_in_a_reading(decoder: str) -> None:
    _need("two_cities.wav", "endgame_nagg_nell.wav")
    from services.voice.engine import make_engine

    engine = make_engine("spotter", decoder=decoder)
    assert (getattr(engine, "decoder", None) is not None) == (decoder == "on")
    rows = {r.name: score(stream(engine, r, SegmenterConfig()), r, Policy.from_knowledge()) for r in wheel_recordings()}
    reading, dialogue = rows["two_cities.wav"], rows["endgame_nagg_nell.wav"]
    assert reading["utterances"] >= 7 and reading["published"] == {}  # 44 s of a person reading: cut every 6 s
    assert dialogue["published"] == {"yes": 2, "no": 1} and dialogue["heard"] == 3
    reader = next(r for r in wheel_recordings() if r.name == "two_cities.wav")
    alone = score_words(engine, word_clips(reader), Policy.from_knowledge())  # each of the person's words alone
    assert alone["other_words"] >= 100 and alone["other_words_taken"] <= 3  # none on this machine (stop 45: 0 of 106)


def test_two_people_on_a_telephone_line_and_a_voice_saying_beckett_give_no_command() -> None:
    _need("sample.wav", "beckett.wav")
    from services.voice.engine import make_engine

    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    recs = {r.name: r for r in wheel_recordings()}
    phone, beckett = recs["sample.wav"], recs["beckett.wav"]
    assert len(phone.transcript) == 13 and phone.transcript[0] == "Hello?"  # the wheel's own transcript, sample.stm
    for rec in (phone, beckett):
        assert score(stream(engine, rec, SegmenterConfig()), rec, policy)["published"] == {}
    alone = score_words(engine, word_clips(phone), policy)  # each word of the conversation alone
    assert alone["other_words"] >= 60 and alone["other_words_taken"] <= 3  # stop 108: 1 of 70 ("hello" -> down)
    assert alone["go_walks"] == 0


def test_a_recordings_wheel_not_downloaded_is_named_with_how_to_fetch_it(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit, match="./run setup downloads them"):
        wheel_recordings(tmp_path)
    err = capsys.readouterr().err
    assert "sample.wav" in err and f"pip download --no-deps -d {tmp_path}" in err and "pyannote.audio==4.0.7" in err


def test_a_recording_is_read_from_its_wheel_file(tmp_path: Path) -> None:
    import io
    import wave
    import zipfile

    buf = io.BytesIO()
    with wave.open(buf, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(16000)
        w.writeframes(b"\x00\x10" * 16000)
    with zipfile.ZipFile(tmp_path / "pyannote_audio-4.0.7-py3-none-any.whl", "w") as z:
        z.writestr("pyannote/audio/sample/sample.wav", buf.getvalue())
        z.writestr("pyannote/audio/sample/sample.stm", "sample 1 A 0.1 0.9 Hello?\nsample 1 B 1.0 1.5 Yes.\n")
    (rec,) = wheel_recordings(tmp_path)
    assert rec.name == "sample.wav" and rec.transcript == ("Hello?", "Yes.") and rec.samples.size == 16000
