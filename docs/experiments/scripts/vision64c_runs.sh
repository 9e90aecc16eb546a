#!/bin/bash
# round vision64c's rule runs (docs/experiments/rules/vision64c_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE heldout or blind (vision36_runs.sh), or "clips" (bench/vision_clips.py, seeds 3163 and 3167, base and
# variant side by side).
# Table: vision36d_rule_table.py $OUT 0 10289,10301 1291,1297
export V="faint_veto_contrast=1"
export W=${W:-/tmp/s111/wt64c} OUT=${OUT:-/tmp/s111/v64c/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export HELDOUT_SEEDS="10289 10301" BLIND_SEEDS="1291 1297"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = clips ]; then
  cd $W
  for s in 3163 3167; do
    .venv/bin/python bench/vision_clips.py --clips 100 --seed $s > $OUT/clips_base_$s.txt 2>&1 &
    .venv/bin/python bench/vision_clips.py --clips 100 --seed $s $SETS > $OUT/clips_var_$s.txt 2>&1
    wait
  done
  exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
