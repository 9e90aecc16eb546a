"""voice7: populate the round-6 mel cache (dataset.indexed_mels) for the proxy's splits (not part of the repo).

    PYTHONPATH=$PWD nice -n 10 python /work/notes/runs/voice7_render.py [--every K] SPLIT...

--every K: only the recipes with index % K == 0 of each split (a fixed subset; cached under its own key)."""
from __future__ import annotations
import sys, time
sys.path.insert(0, "/work/notes/runs")


def main() -> None:
    import voice_exp as ve
    from services.voice.training import dataset
    args = sys.argv[1:]
    every = 1
    if args and args[0] == "--every":
        every = int(args[1]); args = args[2:]
    for sp in args:
        rec = dataset.recipes(sp, ve.SIZES, ve.SEED)
        if every > 1:
            rec = rec[::every]
        t0 = time.time()
        mel, y, idx = dataset.indexed_mels(rec, 2, progress=False)
        print(sp, f"every={every}", "recipes", len(rec), "rows", len(y), "key", dataset._key(rec),
              "s", round(time.time() - t0), time.strftime("%H:%M:%S"), flush=True)


if __name__ == "__main__":
    main()
