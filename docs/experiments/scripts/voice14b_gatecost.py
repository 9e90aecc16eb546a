"""What the walk gate costs: of the held-out "go"s the default head is sure of, how many the gate turns into asks."""
import sys
sys.path.insert(0, "/work/main/bench"); sys.path.insert(0, "/work/main")
import __main__, voice_bench
from voice_bench import heldout_items, OTHER
__main__.Item = voice_bench.Item
from services.voice.engine_spotter import SpotterEngine
from services.voice.training import corpus
GO = corpus.VOCABULARY.index("go")
for seed in (1, 2027):
    items = [it for it in heldout_items(seed, 2) if it.label == GO]
    gated, plain = SpotterEngine.from_path(), SpotterEngine.from_path(None, "none")
    n = sure = walk = 0
    for it in items:
        a, b = plain.recognise(it.pcm), gated.recognise(it.pcm)
        n += 1
        sure += (a.command is not None and a.command.value == "go" and a.confidence >= 0.85)
        walk += (b.command is not None and b.command.value == "go" and b.confidence >= 0.85)
    print(f"seed {seed}: {n} held-out go clips; the head alone would walk on {sure}, with the gate {walk}")
from services.voice.spotter.head import SPEECH_EMBEDDING_HEAD
old = SpotterEngine.from_path(SPEECH_EMBEDDING_HEAD)
for seed in (1, 2027):
    items = [it for it in heldout_items(seed, 2) if it.label == GO]
    w = sum(1 for it in items if (r := old.recognise(it.pcm)).command is not None and r.command.value == "go" and r.confidence >= 0.85)
    print(f"seed {seed}: the speech-embedding head walks at once on {w} of {len(items)}")
