"""Stop 74, tuning clips only (round voice37d's default): commands and other words heard at each level, split by whether the utterance was found by the
first VAD or only by the second (lifted) one, with the engine's published confidence; `voice37d_lifted_table.py` counts them for each bar on the second's.
    .venv/bin/python docs/experiments/scripts/voice37d_lifted_bar.py -44,-38,-32 TAG [CACHE]   # /tmp/voice37d_lifted_TAG.json"""
import json, sys
from pathlib import Path
import numpy as np
ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT)); sys.path.insert(0, str(ROOT / "docs/experiments/scripts"))
from bench.voice_bench import OTHER, Item, Policy  # noqa
from bench.voice_levels import at_level, in_room, through_mic
from bench.voice_walking import LEAD_S, CHUNK
from services.voice.engine import make_engine
from services.voice.segmenter import Segmenter, SegmenterConfig
from voice37_tune import tune_items

if __name__ == "__main__":
    items = tune_items(Path(sys.argv[3] if len(sys.argv) > 3 else "/tmp/s71/voice36_tune_clips.pickle"), 40, 200, 37)
    engine = make_engine("spotter")
    rows = []
    for peak in [float(p) for p in sys.argv[1].split(",")]:
        rng = np.random.default_rng(37)
        for it in items:
            speech = np.frombuffer(it.pcm, "<i2") / 32768.0
            x = np.clip(through_mic(in_room(at_level(speech, peak), -70.0, rng), 48000), -1, 1)
            pcm = (x * 32767).astype("<i2").tobytes()
            seg = Segmenter(SegmenterConfig(), recognise=engine.recognise)
            second_ids = set()
            orig = seg._with_second
            def spy(mine, second, final=False, orig=orig, second_ids=second_ids):
                out = orig(mine, second, final)
                mine_ids = {id(s) for s in mine}
                second_ids.update(id(s) for s in out if id(s) not in mine_ids)
                return out
            seg._with_second = spy
            segs = []
            for k in range(0, len(pcm), CHUNK):
                segs += seg.feed(pcm[k:k + CHUNK])
            segs += seg.flush()
            word_end = LEAD_S + speech.size / 16000
            heard = []
            for s in segs:
                if s.start_s < word_end and s.end_s > LEAD_S:
                    rec = s.recognition or engine.recognise(s.pcm)
                    heard.append((rec.command.value if rec.command else None, rec.confidence, id(s) in second_ids))
            rows.append({"peak": peak, "label": int(it.label), "heard": heard})
        print(peak, flush=True)
    Path(f"/tmp/voice37d_lifted_{sys.argv[2]}.json").write_text(json.dumps(rows))
