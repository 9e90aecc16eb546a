import json, sys
sys.path.insert(0, "/work/main")
import multiprocessing
sys.argv = [sys.argv[0], "73"]
exec(open("docs/experiments/scripts/voice35_probe.py").read().split('if __name__ == "__main__":')[0])
from collections import Counter
if __name__ == "__main__":
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        clips = [c for c in pool.map(_render_phrase, jobs, chunksize=8) if c is not None]
    off, on = SpotterEngine.from_path(), SpotterEngine.from_path(down_in_phrase=True)
    res = Counter()
    for c in clips:
        a, b = off.recognise(c.pcm), on.recognise(c.pcm)
        res[(c.group, a.command.value if a.command else None, b.command.value if b.command else None)] += 1
    for k in sorted(res, key=str): print(k, res[k])
