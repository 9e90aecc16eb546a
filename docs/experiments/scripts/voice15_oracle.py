import sys, numpy as np
sys.argv=['x']
from bench.voice_bench import Item
from bench.voice_walking import pick, heldout_items, mix, OTHER, WORDS, SAMPLE_RATE, to_pcm
from bench.ego_noise import ego_noise, EgoNoiseModel
from services.voice.engine import make_engine
from services.voice.synth import noise
eng = make_engine("spotter")
clips = pick(heldout_items(1, 2), 8, 1)
rng = np.random.default_rng(0)
for kind in ("walk", "stand", "white", "pink"):
    for snr in (20, 10, 5, 0):
        ok = n = oo = on = 0
        for it in clips:
            sp = np.frombuffer(it.pcm, "<i2") / 32768.0
            pad = int(0.25 * SAMPLE_RATE)
            L = sp.size + 2 * pad
            if kind in ("walk", "stand"):
                z = ego_noise(L / SAMPLE_RATE + 0.01, rng, EgoNoiseModel(walking=kind == "walk"))[:L]
            else:
                z = noise(kind, L, rng); z = z / np.sqrt(np.mean(z**2))
            x = np.clip(mix(sp, z, snr, pad), -1, 1)
            r = eng.recognise(to_pcm(x))
            if it.label < OTHER:
                n += 1; ok += r.command is not None and r.command.value == WORDS[it.label] and r.confidence >= 0.5
            else:
                on += 1; oo += r.command is not None and r.confidence >= 0.5
        print(kind, snr, f"acc {ok/n:.3f} oov {oo/on:.3f} (n {n}/{on})", flush=True)
