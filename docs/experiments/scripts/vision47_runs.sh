#!/bin/bash
# round vision47's rule runs (docs/experiments/rules/vision47_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's code ($W); STAGE s1, heldout, blind or gates; "probe" runs vision47_round_probe.py on
# seed 2 ($PROBE_SEED) for base and variant in one process; "clips" runs bench/vision_clips.py on seed 2999 for
# both, side by side. V, S1_SEEDS, PROBE_SEED: another round's (vision47b_runs.sh).
# Table: vision36d_rule_table.py $OUT 7168,7169 6151,8429 787,821
export V=${V:-"propose_sure=0,0.6,0 propose_sure_thresholds=0.01,0.75,0.05 propose_o_clear=0.05"}
export W=${W:-/tmp/s98/wt} OUT=${OUT:-/tmp/s98/v47/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS=${S1_SEEDS:-"7168 7169"} HELDOUT_SEEDS="6151 8429" BLIND_SEEDS="787 821"
mkdir -p $OUT
if [ "$1" = probe ]; then
  cd $W && exec .venv/bin/python docs/experiments/scripts/vision47_round_probe.py ${PROBE_SEED:-2} 150 "base" "var $V" > $OUT/probe.txt 2>&1
fi
if [ "$1" = clips ]; then
  cd $W
  SETS=""; for v in $V; do SETS="$SETS --set $v"; done
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 2999 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 2999 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
