"""Tune-only check of the implementation: recognise() with stop_in_long on, the probe's clips (seed 71)."""
import sys
sys.path.insert(0, "/work/main")
import multiprocessing
from collections import Counter
sys.argv = sys.argv[:1]
import importlib.util
spec = importlib.util.spec_from_file_location("probe", "docs/experiments/scripts/voice33_probe.py"); probe = importlib.util.module_from_spec(spec); spec.loader.exec_module(probe)
from services.voice.engine_spotter import SpotterEngine
if __name__ == "__main__":
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        clips = [c for c in pool.map(probe._render_phrase, probe.jobs, chunksize=8) if c is not None]
    for flag in (False, True):
        eng = SpotterEngine.from_path(stop_in_long=flag)
        res = Counter()
        for c in clips:
            r = eng.recognise(c.pcm)
            res[(c.group, r.command.value if r.command else "none")] += 1
        print("stop_in_long", flag, dict(sorted(res.items())))
