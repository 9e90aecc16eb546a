#!/bin/bash
# round vision49's rule runs (docs/experiments/rules/vision49_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (round vision47's round-things probe, seed 4,
# 150 frames a kind) or "clips" (bench/vision_clips.py, seed 3023, base and variant side by side).
# Table: vision36d_rule_table.py $OUT 7178,7179 9241,9349 1031,1033
export V="o_clear=0.05"
export W=${W:-/tmp/s99/wt49} OUT=${OUT:-/tmp/s99/v49/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7178 7179" HELDOUT_SEEDS="9241 9349" BLIND_SEEDS="1031 1033"
mkdir -p $OUT
if [ "$1" = probe ]; then
  cd $W && exec .venv/bin/python docs/experiments/scripts/vision47_round_probe.py 4 150 "base" "var $V" > $OUT/probe.txt 2>&1
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3023 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3023 --set $V > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
