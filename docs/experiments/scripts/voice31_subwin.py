"""Probe (tune voices only): 'stop' in sub-windows of utterances the head refused."""
import sys, random, pickle
from collections import Counter, defaultdict
import numpy as np
sys.path.insert(0, '/work/main')
from bench.voice_phrases import GROUPS
from services.voice.training import dataset, corpus, tts
from services.voice.synth import OOV_TUNE
from services.voice.engine import make_engine
from services.voice.audio import SAMPLE_RATE
import multiprocessing

def render(r):
    try: return r, dataset.render_utterance(r)
    except tts.TtsError: return r, None

if __name__ == '__main__':
    rng = random.Random(int(sys.argv[1]))
    voices = corpus.voices('tune')
    jobs = []
    for g, (_, phrases) in GROUPS.items():
        for p in phrases:
            for k in range(6):
                jobs.append(dataset.Recipe(p, 99, rng.choice(voices), rng.choice((0.85,1.0,1.15)), 1.0, rng.randrange(2**31), float(k%2)))
    words = [w for w in OOV_TUNE if w not in corpus.forbidden_negatives()]
    for w in words:
        for k in range(2):
            jobs.append(dataset.Recipe(w, 98, rng.choice(voices), rng.choice((0.85,1.0,1.15)), 1.0, rng.randrange(2**31), float(k%2)))
    for i, w in enumerate(corpus.VOCABULARY):
        for k in range(20):
            jobs.append(dataset.Recipe(w, i, rng.choice(voices), rng.choice((0.85,1.0,1.15)), 1.0, rng.randrange(2**31), float(k%2)))
    with multiprocessing.get_context('spawn').Pool(2) as pool:
        out = [x for x in pool.map(render, jobs, chunksize=8) if x[1] is not None]
    eng = make_engine('spotter')
    head = eng.head; stop = head.vocabulary.index('stop'); n = len(head.vocabulary)
    rows = []
    for r, pcm in out:
        rec = eng.recognise(pcm)
        L = len(pcm)//2/SAMPLE_RATE
        wins = {}
        for W in (0.5, 0.6, 0.7, 0.8):
            best = 0.0
            hop = int(0.1*SAMPLE_RATE)*2; w = int(W*SAMPLE_RATE)*2
            if len(pcm) > w:
                for s in range(0, len(pcm)-w+1, hop):
                    p = head.probabilities(eng.embedder.utterance(pcm[s:s+w]))[0]
                    if int(p.argmax()) == stop:
                        best = max(best, head.confidence(stop, float(p[stop])))
            wins[W] = best
        rows.append((r.text, r.label, r.voice, L, rec.command.value if rec.command else None, rec.confidence, wins))
    pickle.dump(rows, open(f'/tmp/s57/subwin_{sys.argv[1]}.pkl','wb'))
    print(len(rows))
