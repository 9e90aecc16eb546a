"""Stop 74, tuning clips only (round voice37d's default, its hold set to 0): the second (lifted) VAD's utterances that no utterance of the first overlaps: their length, and
how long after each ends the first VAD starts one (a fragment of a loud word's onset) or never (a far word).
The tune clips through a 48 kHz microphone's path in a quiet room (`voice37_tune.py`'s), at the peaks given.
    .venv/bin/python docs/experiments/scripts/voice37d_fragments.py -44,-38,-32 TAG [CACHE]   # writes /tmp/voice37d_fragments_TAG.json"""
import json, sys
from dataclasses import replace
from pathlib import Path
import numpy as np
ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT)); sys.path.insert(0, str(ROOT / "docs/experiments/scripts"))
from bench.voice_bench import OTHER, Item  # noqa
from bench.voice_levels import at_level, in_room, through_mic
from bench.voice_walking import LEAD_S
from services.voice.audio import SAMPLE_RATE
from services.voice.segmenter import Segmenter, SegmenterConfig
from voice37_tune import tune_items

if __name__ == "__main__":
    items = tune_items(Path(sys.argv[3] if len(sys.argv) > 3 else "/tmp/s71/voice36_tune_clips.pickle"), 40, 200, 37)
    peaks = [float(p) for p in sys.argv[1].split(",")]
    config = replace(SegmenterConfig(), vad_lift_hold_s=0.0)
    rows = []
    for peak in peaks:
        rng = np.random.default_rng(37)
        for it in items:
            speech = np.frombuffer(it.pcm, "<i2") / 32768.0
            x = np.clip(through_mic(in_room(at_level(speech, peak), -70.0, rng), 48000), -1, 1)
            pcm = (x * 32767).astype("<i2").tobytes()
            seg = Segmenter(config)
            firsts, seconds = [], []
            orig = seg._with_second
            def spy(mine, second, final=False):
                seconds.extend((s.start_s, s.end_s) for s in second)
                return orig(mine, second, final)
            seg._with_second = spy
            for k in range(0, len(pcm), 960):
                for s in seg.feed(pcm[k:k + 960]):
                    pass
            seg.flush()
            firsts = list(seg._spans)
            for a, b in seconds:
                if any(s < b and a < e for s, e in firsts):
                    continue
                after = [s - b for s, e in firsts if s >= b]
                rows.append({"peak": peak, "label": int(it.label), "start": a, "end": b, "len": b - a,
                             "gap": min(after) if after else None, "word_start": LEAD_S})
        print(peak, len(rows), flush=True)
    Path(f"/tmp/voice37d_fragments_{sys.argv[2]}.json").write_text(json.dumps(rows))
