"""Round 17: voice_bench's stream latency alone (40 clean held-out commands in the faint hiss), with the clear
window off and at 0.09 s, each twice, back to back."""
import argparse, json, sys
sys.path.insert(0, ".")
from bench.voice_bench import heldout_items, stream_latency
from services.voice.training import corpus
from services.voice.engine import make_engine
from services.voice.segmenter import SegmenterConfig

ap = argparse.ArgumentParser()
ap.add_argument("--seed", type=int, required=True)
ap.add_argument("--runs", type=int, default=2)
args = ap.parse_args()
items = [it for it in heldout_items(args.seed, 2) if it.family not in corpus.HELDOUT_EXTRA]
engine = make_engine("spotter")
for run in range(args.runs):
    for name, clear in (("control", None), ("candidate", 0.09)):
        row = stream_latency(engine, items, config=SegmenterConfig(clear_quiet_s=clear))
        print(json.dumps({"run": run + 1, "config": name, **row}), flush=True)
