"""Probe 2 (tune voices only): false stops from sub-windows on tune one-edit neighbours and tune words."""
import sys, random, pickle, time
import numpy as np
sys.path.insert(0, '/work/main')
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
    nb = dataset.neighbours(dataset.Sizes(), 12)['tune']
    for w in nb:
        for k in range(6):
            jobs.append(dataset.Recipe(w, 97, rng.choice(voices), rng.choice((0.85,1.0,1.15)), 1.0, rng.randrange(2**31), float(k%2)))
    words = [w for w in OOV_TUNE if w not in corpus.forbidden_negatives()]
    for w in words:
        for k in range(6):
            jobs.append(dataset.Recipe(w, 98, rng.choice(voices), rng.choice((0.85,1.0,1.15)), 1.0, rng.randrange(2**31), float(k%2)))
    with multiprocessing.get_context('spawn').Pool(2) as pool:
        out = [x for x in pool.map(render, jobs, chunksize=8) if x[1] is not None]
    eng = make_engine('spotter')
    head = eng.head; stop = head.vocabulary.index('stop')
    rows = []; te = []
    for r, pcm in out:
        rec = eng.recognise(pcm)
        wins = {}
        for W, hop_s in ((0.7, 0.1), (0.7, 0.2), (0.6, 0.15)):
            best = 0.0
            hop = int(hop_s*SAMPLE_RATE)*2; w = int(W*SAMPLE_RATE)*2
            if rec.command is None and len(pcm) > w and len(pcm)//2/SAMPLE_RATE <= 1.7:
                for s in range(0, len(pcm)-w+1, hop):
                    t0 = time.perf_counter()
                    p = head.probabilities(eng.embedder.utterance(pcm[s:s+w]))[0]
                    te.append(time.perf_counter()-t0)
                    if int(p.argmax()) == stop:
                        best = max(best, head.confidence(stop, float(p[stop])))
            wins[(W, hop_s)] = best
        rows.append((r.text, r.label, r.voice, len(pcm)//2/SAMPLE_RATE, rec.command.value if rec.command else None, rec.confidence, wins))
    pickle.dump(rows, open(f'/tmp/s57/subwin2_{sys.argv[1]}.pkl','wb'))
    print(len(rows), 'embed ms p50', 1000*np.median(te))
    for key in ((0.7, 0.1), (0.7, 0.2), (0.6, 0.15)):
        for thr in (0.5, 0.7, 0.85):
            for lab in (97, 98):
                sel = [r for r in rows if r[1] == lab]
                base = sum(r[4] is not None for r in sel); st = sum(r[4] == 'stop' for r in sel)
                resc = [r[0] for r in sel if r[4] is None and r[6][key] >= thr]
                print(key, thr, 'neighbours' if lab == 97 else 'oov', f'accepted {base}/{len(sel)} (stop {st}), +{len(resc)} stops:', resc)
