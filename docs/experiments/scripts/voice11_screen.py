"""Round 11 intelligibility screen (rule in /work/notes/voice11_rule.txt)."""
import json, numpy as np
from services.voice.spotter.head import Head
from services.voice.spotter.features import Embedder, speech_seconds, MAX_SPEECH_S
from services.voice.training import tts, corpus, dataset
head = Head.load(); emb = Embedder()
words = corpus.VOCABULARY
variants = [(0.9, 1.0), (1.0, 1.0), (1.1, 1.0), (1.0, 1.15)]
negs = [w for ws in corpus.NEIGHBOURS_TRAIN.values() for w in ws] + corpus.common_words(100, 12)
out = {}
for v in tts.FOREIGN_VOICES:
    right = 0; conf = []
    for i, w in enumerate(words):
        for k, (s, p) in enumerate(variants):
            pcm = dataset.render(dataset.Recipe(w, i, f"foreign:{v}", s, p, 1000 + k, 0.0))
            if pcm is None: conf.append((w, "long")); continue
            pr = head.probabilities(emb.utterance(pcm))[0]
            right += int(pr.argmax() == i); conf.append((w, head.classes[int(pr.argmax())]))
    fails = 0
    for w in negs:
        try: tts.synthesise(w, f"foreign:{v}")
        except tts.TtsError: fails += 1
    out[v] = {"right": right, "of": 28, "keep": right >= 10, "neg_fail": fails, "n_neg": len(negs)}
    print(v, out[v], [c for c in conf if c[0] != c[1]][:12], flush=True)
json.dump(out, open("/work/notes/runs/voice11-screen.json", "w"), indent=1)
