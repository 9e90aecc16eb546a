#!/bin/bash
# round vision42b's rule runs (docs/experiments/rules/vision42b_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's code ($W); STAGE s1, heldout, blind or gates; "clips" runs bench/vision_clips.py on seed
# 2971 for base and variant, side by side.
# Table: vision36d_rule_table.py $OUT 7144,7145 8263,6607 479,499
export V="propose_sure=0,0.6,0 propose_sure_thresholds=0.3,0.75,0.9"
export W=${W:-/tmp/s75/w42} OUT=${OUT:-/tmp/s75/v42b/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7144 7145" HELDOUT_SEEDS="8263 6607" BLIND_SEEDS="479 499"
if [ "$1" = clips ]; then
  mkdir -p $OUT && cd $W
  SETS=""; for v in $V; do SETS="$SETS --set $v"; done
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 2971 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 2971 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
