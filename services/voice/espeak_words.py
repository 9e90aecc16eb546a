"""When espeak-ng says each word of a sentence: its own word events, from its library.

The robot's voice is espeak-ng's (the speech service), and the voice service renders each sentence again with the
command-line program (`synth.speak`, `robot_voice.py`). The program prints no timings; the library it runs on,
libespeak-ng (the same package, Debian's libespeak-ng1), reports a word event as it reaches each word: where the word
is in the text and how far into the sound. Both run the same synthesiser with the same voice and rate, so the events
place each word in the program's rendering too (checked: the speech begins and ends within a few samples of each
other; the program only adds trailing silence). The library keeps one global synthesiser, so calls are serialised.
"""

from __future__ import annotations

import ctypes
import threading
from dataclasses import dataclass

from services.voice.synth import SynthError

LIBRARY = "libespeak-ng.so.1"
_SYNCHRONOUS = 2  # espeak_AUDIO_OUTPUT: the callback is called during espeak_Synth, which returns when done
_RATE = 1  # espeak_PARAMETER espeakRATE: words a minute
_CHARACTER = 1  # espeak_POSITION_TYPE POS_CHARACTER
_LIST_END, _WORD = 0, 1  # espeak_EVENT_TYPE


class _Event(ctypes.Structure):
    """espeak_EVENT (speak_lib.h)."""

    _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint), ("text_position", ctypes.c_int),
                ("length", ctypes.c_int), ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                ("user_data", ctypes.c_void_p), ("id", ctypes.c_char * 8)]


_Callback = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(_Event))


@dataclass(frozen=True)
class Word:
    start: int
    """Where the word begins in the text (characters, from 0)."""
    length: int
    """Its length in the text (characters)."""
    at_s: float
    """How far into the sound espeak-ng begins saying it, seconds."""


class _Library:
    """libespeak-ng, loaded and initialised once, with its callback kept alive."""

    def __init__(self) -> None:
        try:
            self.lib = ctypes.CDLL(LIBRARY)
        except OSError as exc:
            raise SynthError(f"{LIBRARY} cannot be loaded ({exc}): apt-get install libespeak-ng1") from None
        self.rate = self.lib.espeak_Initialize(_SYNCHRONOUS, 0, None, 0)
        if self.rate <= 0:
            raise SynthError(f"{LIBRARY} would not start (espeak_Initialize returned {self.rate})")
        self.words: list[Word] = []
        self.callback = _Callback(self._heard)
        self.lib.espeak_SetSynthCallback(self.callback)

    def _heard(self, _wav: object, _n: int, events: ctypes.Array[_Event]) -> int:
        k = 0
        while events[k].type != _LIST_END:
            e = events[k]
            if e.type == _WORD:
                self.words.append(Word(e.text_position - 1, e.length, e.audio_position / 1000.0))
            k += 1
        return 0  # go on


_lock = threading.Lock()
_library: _Library | None = None


def words(text: str, voice: str, rate: int) -> list[Word]:
    """espeak-ng's words of `text` said with `voice` at `rate` words a minute, in order. SynthError where the library
    will not load or refuses the voice or the text."""
    global _library
    with _lock:
        if _library is None:
            _library = _Library()
        lib = _library.lib
        if lib.espeak_SetVoiceByName(voice.encode()) != 0:
            raise SynthError(f"espeak-ng has no voice {voice!r}")
        lib.espeak_SetParameter(_RATE, int(rate), 0)
        _library.words = []
        data = text.encode()
        if lib.espeak_Synth(data, len(data) + 1, 0, _CHARACTER, 0, 0, None, None) != 0:
            raise SynthError(f"espeak-ng would not say {text!r}")
        return list(_library.words)
