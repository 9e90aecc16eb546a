import pickle, sys
from collections import Counter
sys.path.insert(0,'/work/main')
from bench.voice_phrases import GROUPS
rows = pickle.load(open(sys.argv[1],'rb'))
grp = {p: g for g, (_, ps) in GROUPS.items() for p in ps}
def kind(t, lab):
    if lab == 98: return 'oov word'
    if lab < 98: return 'command word'
    return grp[t]
for W in (0.5, 0.6, 0.7, 0.8):
  for thr in (0.5, 0.7, 0.85):
    for minlen in (0.0, 0.8, 1.0):
      c = Counter(); tot = Counter(); base = Counter()
      for t, lab, v, L, cmd, conf, wins in rows:
        k = kind(t, lab); tot[k] += 1
        base[k] += cmd == 'stop'
        resc = cmd is None and L >= minlen and wins[W] >= thr
        c[k] += (cmd == 'stop') or resc
      print(f'W {W} thr {thr} minlen {minlen}: ' + '; '.join(f'{k} {base[k]}->{c[k]}/{tot[k]}' for k in sorted(tot)))
