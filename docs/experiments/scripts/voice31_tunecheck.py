"""Tune voices: the phrase groups through the engine with and without stop_in_phrase (the implementation)."""
import sys, random, multiprocessing, time
from collections import Counter
sys.path.insert(0, '/work/main')
from bench.voice_phrases import GROUPS, heard
from bench.voice_bench import Policy
from services.voice.training import dataset, corpus, tts
from services.voice.engine_spotter import SpotterEngine

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
    with multiprocessing.get_context('spawn').Pool(2) as pool:
        out = [x for x in pool.map(render, jobs, chunksize=8) if x[1] is not None]
    pol = Policy.from_knowledge()
    grp = {p: g for g, (_, ps) in GROUPS.items() for p in ps}
    for on in (False, True):
        eng = SpotterEngine.from_path(stop_in_phrase=on)
        c = {g: Counter() for g in GROUPS}; t = []
        for r, pcm in out:
            t0 = time.perf_counter(); rec = eng.recognise(pcm); t.append(time.perf_counter() - t0)
            c[grp[r.text]][heard(rec, pol)] += 1
        t.sort()
        print('on' if on else 'off', f'decode p50 {1000*t[len(t)//2]:.0f} ms p90 {1000*t[int(len(t)*0.9)]:.0f} ms')
        for g in GROUPS: print('   ', g, dict(c[g].most_common()))
