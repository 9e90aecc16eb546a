"""Stop 84, tuning data only: does averaging the spotter's embedding over nudged copies steady it?

`voice44_flip_probe.py` found most of a twin hiss draw's chance in the spotter itself. Here the default engine's
embedding of each utterance is replaced by the mean of three: the utterance, and the utterance less `K` samples at its
start or at its end (the copy is centred `K`/2 samples later or earlier in the spotter's 2 s window). Round 37's tune
clips at -3 dBFS in two draws of the hiss (`voice41e_twin_probe.hear`, seeds 37 and 1037): commands heard and other
words taken, each way, and the words the two draws disagree on (lost, gained).

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice44_average_probe.py --cache /tmp/s84/tune.pickle 160
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items  # noqa: E402
from voice41e_twin_probe import hear  # noqa: E402

from bench.voice_bench import Policy  # noqa: E402
from bench.voice_walking import paired  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, required=True)
    ap.add_argument("k", type=int, help="samples taken off one end of each copy")
    args = ap.parse_args()
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    embedder = engine.embedder  # type: ignore[attr-defined]
    plain = embedder.utterance
    k = args.k

    def averaged(pcm: bytes, seed: int = 0) -> np.ndarray:
        copies = [pcm, pcm[2 * k :], pcm[: -2 * k]]
        return np.mean([plain(c, seed) for c in copies], axis=0).astype(np.float32)

    for name, utterance in (("plain", plain), (f"averaged, k={k}", averaged)):
        embedder.utterance = utterance
        heard: list[str] = []
        for seed in (37, 1037):
            each, taken = hear(items, engine, policy, -3.0, 0.0, SegmenterConfig(), seed)
            heard.append("".join("01"[x] for x in each))
            print(f"{name}, hiss {seed}: commands heard {sum(each)}/{len(each)}, other words taken {taken}", flush=True)
        print(f"{name}: the draws disagree on {sum(paired(heard[0], heard[1]))} commands", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
