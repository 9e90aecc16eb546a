"""Stop 74: `voice37d_lifted_bar.py`'s files, per peak: commands heard / other words taken when an utterance only the
second (lifted) VAD found must reach each bar of confidence (0.5: every one the reasoner acts on; 1.01: none).
    python docs/experiments/scripts/voice37d_lifted_table.py /tmp/voice37d_lifted_*.json"""
import json, sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
from bench.voice_bench import OTHER, Policy
from schemas.messages import Command
WORDS = ['stand', 'down', 'yes', 'no', 'go', 'stop', 'why']
pol = Policy.from_knowledge()
rows = []
for f in sys.argv[1:]:
    rows += json.load(open(f))
for peak in sorted({r['peak'] for r in rows}):
    rs = [r for r in rows if r['peak'] == peak]
    line = []
    for bar in (0.5, 0.6, 0.7, 0.8, 0.9, 1.01):
        ok = oov = n_cmd = n_oov = 0
        for r in rs:
            got = None
            for cmd, conf, lifted in r['heard']:
                if cmd is None or (lifted and conf < bar):
                    continue
                got = (cmd, conf); break
            taken = pol.takes(Command(got[0]), got[1]) if got else None
            if r['label'] < OTHER:
                n_cmd += 1; ok += taken is not None and got[0] == WORDS[r['label']]
            else:
                n_oov += 1; oov += taken is not None
        line.append(f"{bar}: {ok / n_cmd:.3f}/{100 * oov / n_oov:.1f}%")
    lifted_share = sum(any(h[2] for h in r['heard']) for r in rs) / len(rs)
    print(peak, f"lifted {lifted_share:.2f}", " | ".join(line))
