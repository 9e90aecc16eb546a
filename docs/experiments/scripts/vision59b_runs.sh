#!/bin/bash
# round vision59b's rule runs (docs/experiments/rules/vision59b_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (bench/vision_bench.py, tuning seed 7217, 1,000
# frames, every mark drawn by hand and every finger varied) or "clips" (bench/vision_clips.py, seed 3097).
# Table: vision36d_rule_table.py $OUT 7215,7216 10187,10193 1213,1217
export V="danger_contrast_ratio=0.8"
export W=${W:-/tmp/s104/wt59b} OUT=${OUT:-/tmp/s104/v59b/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7215 7216" HELDOUT_SEEDS="10187 10193" BLIND_SEEDS="1213 1217"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = probe ]; then
  cd $W
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7217 --hand-drawn 1 --hand-variety 1 \
    --json > $OUT/probe_base.json 2> $OUT/probe_base.err &
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7217 --hand-drawn 1 --hand-variety 1 \
    $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
  wait; exit
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3097 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3097 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
