"""Tune-only probe: "stop" in utterances longer than MAX_SPEECH_S, windows across the whole utterance."""
import random, sys, time
from collections import Counter
sys.path.insert(0, "/work/main")
import multiprocessing
from bench.voice_phrases import _render_phrase
from services.voice.engine_spotter import SpotterEngine
from services.voice.spotter.features import MAX_SPEECH_S, speech_seconds
from services.voice.training import corpus, dataset

WITH = ("robot, please stop walking now", "hey, stop, you are going to fall over", "I think you should stop right there",
        "okay, that is enough now, please stop", "stop, stop, there is a wall in front of you",
        "would you please stop moving for a moment", "listen to me and stop at once", "you have to stop before the table")
WITHOUT = ("we went to the store at the top of the street", "she started the tour at the old stadium",
           "please put a stamp on the top of the letter", "I want to go to the shop tomorrow morning",
           "could you tell me a story about the stars", "the bus was late again this morning",
           "he stepped on the stone and almost fell", "they stayed at home and watched the storm",
           "turn left at the second traffic light", "what time does the train leave today")
seed = int(sys.argv[1]) if len(sys.argv) > 1 else 71
rng = random.Random(f"longstop:{seed}")
voices = corpus.voices("tune")
jobs = [(g, dataset.Recipe(p, len(corpus.VOCABULARY), rng.choice(voices), rng.choice((0.85, 1.0, 1.15)), 1.0,
                           rng.randrange(2**31), float(k % 2)))
        for g, ps in (("with", WITH), ("without", WITHOUT)) for p in ps for k in range(8)]
if __name__ == "__main__":
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        clips = [c for c in pool.map(_render_phrase, jobs, chunksize=8) if c is not None]
    eng = SpotterEngine.from_path()
    res = Counter(); t = []
    for c in clips:
        long = speech_seconds(c.pcm) > MAX_SPEECH_S
        rec = eng.recognise(c.pcm)
        t0 = time.perf_counter()
        hit = eng._stop_within(c.pcm) if long else None
        t.append(time.perf_counter() - t0)
        for at in (0.7, 0.8, 0.85):
            ok = hit is not None and hit[1] >= at
            res[(c.group, "long" if long else "short", at, "stop" if (ok if long else rec.command is not None and rec.command.value == "stop") else "no")] += 1
    for k in sorted(res): print(k, res[k])
    import numpy as np; print("window time p50/max ms", np.percentile(t, 50) * 1000, max(t) * 1000)
