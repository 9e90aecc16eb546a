#!/bin/bash
# round vision48's rule runs (docs/experiments/rules/vision48_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (vision48_dot_probe.py, seed 2, 300 frames a
# kind) or "clips" (bench/vision_clips.py, seed 3011, base and variant side by side).
# Table: vision36d_rule_table.py $OUT 7176,7177 7919,9133 1009,1013
export V="propose_t_fill=0.7"
export W=${W:-/tmp/s99/wt} OUT=${OUT:-/tmp/s99/v48/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7176 7177" HELDOUT_SEEDS="7919 9133" BLIND_SEEDS="1009 1013"
mkdir -p $OUT
if [ "$1" = probe ]; then
  cd $W && exec .venv/bin/python docs/experiments/scripts/vision48_dot_probe.py 2 300 "base" "var $V" > $OUT/probe.txt 2>&1
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3011 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3011 --set $V > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
