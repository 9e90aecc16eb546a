import json
from collections import Counter
rows = [json.loads(l) for l in open("/tmp/voice35_probe.jsonl")]
for at in (0.6, 0.7, 0.8, 0.85):
    print("at", at)
    for g in ("stand", "down", "no", "why", "without"):
        rs = [r for r in rows if r["group"] == g]
        head = Counter(r["head"] for r in rs)
        win = Counter()
        for r in rs:
            if r["head"] is None and not r["long"]:
                hits = [(c, w) for w, c in r["windows"] if c >= at and w != "go"]
                if hits:
                    win[max(hits)[1]] += 1
        print(f"  {g:8} n {len(rs)} head {dict(head)}  windows add {dict(win)}")
false = [(r["text"], max((c, w) for w, c in r["windows"] if w != "go")) for r in rows if r["group"] == "without" and r["head"] is None and not r["long"] and any(c >= 0.7 and w != "go" for w, c in r["windows"])]
print(false)
