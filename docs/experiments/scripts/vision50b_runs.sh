#!/bin/bash
# round vision50b's rule runs (docs/experiments/rules/vision50b_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (vision50_v_probe.py, tuning seed 7190, 1,000
# frames, hand 0.5) or "clips" (bench/vision_clips.py, seed 3041, base and variant side by side).
# Table: vision36d_rule_table.py $OUT 7188,7189 9739,9851 1051,1061
export V="propose_open_side=0.6"
export W=${W:-/tmp/s100/wtb} OUT=${OUT:-/tmp/s100/v50b/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7188 7189" HELDOUT_SEEDS="9739 9851" BLIND_SEEDS="1051 1061"
mkdir -p $OUT
if [ "$1" = probe ]; then
  cd $W && exec .venv/bin/python docs/experiments/scripts/vision50_v_probe.py 7190 1000 0.5 "base" "var $V" > $OUT/probe.txt 2>&1
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3041 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3041 --set $V > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
