"""Tune-only probe: commands other than "stop" said within a phrase ("sit down", "stand up", "oh no", "why not"),
heard through round 31's windows. Per window, the head's most probable command and its confidence."""
import json, random, sys
sys.path.insert(0, "/work/main")
import multiprocessing
from bench.voice_phrases import _render_phrase
from services.voice.engine_spotter import SpotterEngine, PhraseStop
from services.voice.training import corpus, dataset

WITH = {"stand": ("stand up", "please stand", "stand up now", "stand up please", "okay stand"),
        "down": ("sit down", "get down", "lie down", "down please", "sit down now"),
        "no": ("oh no", "no thanks", "no no", "no, not now", "no way"),
        "why": ("why not", "but why", "why is that", "why me", "why now")}
WITHOUT = ("understand", "standard", "downtown", "download", "nobody", "notice", "nowhere", "sundown", "outstanding",
           "slow it", "knowing that", "the stadium", "a good town", "not today", "the white house", "go away",
           "don't go", "let's go", "stop it", "go ahead", "okay then", "sounds good", "thank you", "see you later",
           "what is this", "how are you", "the table is round", "a cup of tea")
seed = int(sys.argv[1]) if len(sys.argv) > 1 else 73
rng = random.Random(f"cmdphrase:{seed}")
voices = corpus.voices("tune")
jobs = [(g, dataset.Recipe(p, len(corpus.VOCABULARY), rng.choice(voices), rng.choice((0.85, 1.0, 1.15)), 1.0,
                           rng.randrange(2**31), float(k % 2)))
        for g, ps in [*WITH.items(), ("without", WITHOUT)] for p in ps for k in range(6)]
if __name__ == "__main__":
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        clips = [c for c in pool.map(_render_phrase, jobs, chunksize=8) if c is not None]
    eng = SpotterEngine.from_path(stop_in_phrase=False)
    ps = PhraseStop()
    out = open("/tmp/voice35_probe.jsonl", "w")
    for c in clips:
        rec = eng.recognise(c.pcm)
        wins = []
        for start, w in ps.windows(c.pcm):
            p = eng.head.probabilities(eng.embedder.utterance(w))[0]
            b = int(p.argmax())
            if b < len(eng.head.vocabulary):
                wins.append((eng.head.vocabulary[b], round(eng.head.confidence(b, float(p[b])), 3)))
        out.write(json.dumps({"group": c.group, "text": c.phrase, "head": rec.command.value if rec.command else None,
                              "head_conf": round(rec.confidence, 3), "windows": wins, "long": rec.text == "(long utterance)"}) + "\n")
