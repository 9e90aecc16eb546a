"""Stop 84, tuning data only: why does another draw of a -70 dBFS hiss turn loud commands over?

Round voice41e's twin probe found 13 of 280 tune commands at -3 dBFS heard in one draw of the room's hiss and not the
other (hiss 67 dB under the voice). Two candidate causes: the hiss moves the VAD's cut (the utterance's start or end
by a frame or more), and the spotter, which centres the utterance in its 2 s window, hears a shifted word; or the
hiss itself, in the same cut, moves the spotter's score. Here round 37's 280 tune commands, each 1.2 s into its own
stream at `--peak` in -70 dBFS hiss (seeds 37 and 1037), through a 48 kHz microphone's path, go through the default
segmenter; for each word, the segment over it in each draw (its start and end) and the spotter's result; then, for
each word, the second draw's stream cut where the first draw's segmenter cut it and recognised again. Prints how many
words flip, how many of those the VAD cut differently, and how many flips remain with the first draw's cut.

    PYTHONPATH=. .venv/bin/python docs/experiments/scripts/voice44_flip_probe.py --cache /tmp/s84/tune.pickle
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items, tuning_stream  # noqa: E402

from bench.voice_bench import OTHER, WORDS, Policy  # noqa: E402
from bench.voice_walking import CHUNK, LEAD_S, rounded_pcm  # noqa: E402
from services.voice.audio import SAMPLE_RATE  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, required=True)
    ap.add_argument("--peak", type=float, default=-3.0)
    args = ap.parse_args()
    items = [it for it in tune_items(args.cache, 40, 200, 37) if it.label < OTHER]
    engine, policy = make_engine("spotter"), Policy.from_knowledge()

    def heard(word: str, pcm: bytes) -> bool:
        rec = engine.recognise(pcm)
        return (rec.command is not None and rec.command.value == word
                and policy.takes(rec.command, rec.confidence) is not None)

    draws: list[list[tuple[bytes, tuple[float, float] | None, bool]]] = []
    for seed in (37, 1037):
        rng = np.random.default_rng(seed)
        out = []
        for it in items:
            speech = np.frombuffer(it.pcm, "<i2") / 32768.0
            x = np.clip(tuning_stream(speech, args.peak, rng), -1.0, 1.0)
            pcm = rounded_pcm(x)
            word_start, word_end = LEAD_S, LEAD_S + speech.size / SAMPLE_RATE
            seg = Segmenter(SegmenterConfig())
            segs = [s for k in range(0, len(pcm), CHUNK) for s in seg.feed(pcm[k : k + CHUNK])] + seg.flush()
            over = [s for s in segs if s.start_s < word_end and s.end_s > word_start]
            first = over[0] if over else None
            out.append((pcm, (first.start_s, first.end_s) if first else None,
                        first is not None and heard(WORDS[it.label], first.pcm)))
        draws.append(out)
        print(f"hiss {seed}: {sum(h for *_, h in out)}/{len(out)} commands heard (first segment over the word)",
              flush=True)
    flips = [i for i in range(len(items)) if draws[0][i][2] != draws[1][i][2]]
    moved = [i for i in flips if draws[0][i][1] != draws[1][i][1]]
    same_cut = 0
    for i in flips:
        cut = draws[0][i][1]
        if cut is None:
            continue
        pcm = draws[1][i][0]
        a, b = round(cut[0] * SAMPLE_RATE) * 2, round(cut[1] * SAMPLE_RATE) * 2
        same_cut += heard(WORDS[items[i].label], pcm[a:b]) != draws[0][i][2]
    shifts = [abs(a[0] - b[0]) + abs(a[1] - b[1])
              for a, b in ((draws[0][i][1], draws[1][i][1]) for i in range(len(items))) if a and b]
    moved_by = [s for s in shifts if s > 0]
    median = float(np.median(moved_by)) if moved_by else 0.0
    print(f"words that flip: {len(flips)}; of them cut differently by the VAD: {len(moved)}; flips left when the "
          f"second draw is cut where the first was: {same_cut}; words cut differently overall: "
          f"{len(moved_by)}/{len(shifts)} (median shift of those {median:.3f} s)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
