"""Round voice53's tuning-side probe: voices no committed head and no candidate head was fitted on, and no bench row
uses (Festival rab and don, round voice29's; Kokoro jf_alpha, jf_gongitsune, jf_tebukuro, round voice22's), saying
the 7 commands and tune words only (OOV_TUNE and the tune one-edit neighbours), as round voice30's probe did.

  render: PYTHONPATH=. python docs/experiments/scripts/voice53_probe.py render DRAW OUT.npz
  score:  PYTHONPATH=. python docs/experiments/scripts/voice53_probe.py score OUT.npz NEW_SE_HEAD

`score` prints, for each engine setting, commands heard (a published "go" counted, whether the robot would walk or
ask), other words accepted, "go" walked unasked, direct false walks, per voice family."""
from __future__ import annotations

import random
import sys
from collections import Counter, defaultdict
from multiprocessing import get_context

import numpy as np

from bench.voice_bench import WALK, Policy
from services.voice.engine_spotter import SpotterEngine
from services.voice.spotter.head import SPEECH_EMBEDDING_HEAD
from services.voice.synth import OOV_TUNE
from services.voice.training import corpus, dataset
from services.voice.training.dataset import OTHER, Recipe

VOICES = (*corpus.RECORDED_GB, *corpus.NEURAL_TRAIN)
COMMANDS_PER_VOICE = 6  # per command word
OTHERS_PER_VOICE = 60


def recipes(draw: int) -> list[Recipe]:
    rng = random.Random(f"voice53:{draw}")
    tune_words = sorted(set(OOV_TUNE) | set(dataset.neighbours(dataset.Sizes(), 12)["tune"]))
    out = []

    def said(word: str, label: int, voice: str) -> None:
        out.append(Recipe(word, label, voice, round(rng.uniform(0.8, 1.25), 3), round(rng.uniform(0.8, 1.3), 3),
                          rng.randrange(2**31), 0.0 if rng.random() < 0.5 else 1.0))

    for v in VOICES:
        for i, w in enumerate(corpus.VOCABULARY):
            for _ in range(COMMANDS_PER_VOICE):
                said(w, i, v)
        for w in rng.sample(tune_words, OTHERS_PER_VOICE):
            said(w, OTHER, v)
    return out


def _render(r: Recipe) -> bytes | None:
    try:
        return dataset.render(r)
    except Exception:  # a voice that cannot say the word: left out, counted
        return None


def render(draw: int, out: str) -> None:
    rs = recipes(draw)
    with get_context("spawn").Pool(2) as pool:
        pcms = pool.map(_render, rs, chunksize=4)
    keep = [(r, p) for r, p in zip(rs, pcms, strict=True) if p]
    print(f"{len(keep)} of {len(rs)} clips rendered", file=sys.stderr)
    np.savez(out, text=[r.text for r, _ in keep], label=[r.label for r, _ in keep], voice=[r.voice for r, _ in keep],
             pcm=np.array([np.frombuffer(p, "<i2") for _, p in keep], dtype=object))


def score(path: str, new_se: str) -> None:
    z = np.load(path, allow_pickle=True)
    settings = {
        "default (old gate, veto off)": dict(walk_gate=None, agree_min=0.0),
        "old gate, veto 0.25 (round 27)": dict(walk_gate=None, agree_min=0.25),
        "new gate, veto off": dict(walk_gate=new_se, agree_min=0.0),
        "new gate, veto 0.25": dict(walk_gate=new_se, agree_min=0.25),
        "new gate, veto 0.1": dict(walk_gate=new_se, agree_min=0.1),
        "old SE head alone": dict(path=SPEECH_EMBEDDING_HEAD, walk_gate="none"),
        "new SE head alone": dict(path=new_se, walk_gate="none"),
    }
    vocab = corpus.VOCABULARY
    policy = Policy.from_knowledge()  # what the reasoner does with a published "go", as the bench counts it
    for name, kw in settings.items():
        eng = SpotterEngine.from_path(**kw)
        tally: dict[str, Counter] = defaultdict(Counter)
        for label, voice, pcm in zip(z["label"], z["voice"], z["pcm"], strict=True):
            fam = "festival" if voice.startswith("festival") else "kokoro"
            rec = eng.recognise(pcm.astype("<i2").tobytes())
            heard = rec.command.value if rec.command else None
            walk = policy.takes(rec.command, rec.confidence) == WALK
            for t in (tally[fam], tally["all"]):
                if label < OTHER:
                    t["commands"] += 1
                    t["heard"] += heard == vocab[label]
                    if vocab[label] == "go":
                        t["go"] += 1
                        t["go walked"] += walk
                else:
                    t["others"] += 1
                    t["accepted"] += heard is not None
                    t["false walks"] += walk
        print(name)
        for fam in ("all", "festival", "kokoro"):
            t = tally[fam]
            print(f"  {fam:9s} heard {t['heard']}/{t['commands']} ({t['heard'] / t['commands']:.3f}), other words "
                  f"{t['accepted']}/{t['others']} ({t['accepted'] / t['others']:.3f}), go walked {t['go walked']}/"
                  f"{t['go']}, false walks {t['false walks']}")
        sys.stdout.flush()


if __name__ == "__main__":
    if sys.argv[1] == "render":
        render(int(sys.argv[2]), sys.argv[3])
    else:
        score(sys.argv[2], sys.argv[3])
