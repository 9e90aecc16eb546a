import json, sys, numpy as np
sys.path.insert(0, "/work/main")
from services.voice.training import dataset
from services.voice.training.train import TrainConfig
from services.voice.engine_spotter import SpotterEngine
rows = [json.loads(l) for l in open("/tmp/voice34_probe.jsonl")]
cfg = TrainConfig()
recs = [r for sp in ("tune", "speakers-tune", "recorded-tune", "neighbours-tune") for r in dataset.recipes(sp, cfg.sizes, cfg.seed)]
cmds = [r for r in recs if r.label < 7][::2]; others = [r for r in recs if r.label == 7][::2]
on, off = SpotterEngine.from_path(warped_look=True), SpotterEngine.from_path(warped_look=False)
n = 0; diff = []
for r in (cmds + others)[:: int(sys.argv[1]) if len(sys.argv) > 1 else 7]:
    pcm = dataset.render(r)
    if pcm is None: continue
    a, b = off.recognise(pcm), on.recognise(pcm)
    if (a.command, round(a.confidence, 3)) != (b.command, round(b.confidence, 3)):
        diff.append((repr(r), a.command, b.command, round(b.confidence, 3), b.detail.get("p"), b.detail.get("warped")))
    n += 1
print(n, "checked;", len(diff), "changed:"); [print(d) for d in diff]
