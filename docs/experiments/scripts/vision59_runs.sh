#!/bin/bash
# round vision59's rule runs (docs/experiments/rules/vision59_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (bench/vision_bench.py, tuning seed 7214, 1,000
# frames, every mark drawn by hand and every finger varied) or "clips" (bench/vision_clips.py, seed 3093).
# Table: vision36d_rule_table.py $OUT 7212,7213 10177,10181 1193,1201
export V="max_contrast_ratio=0.8"
export W=${W:-/tmp/s104/wt59} OUT=${OUT:-/tmp/s104/v59/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7212 7213" HELDOUT_SEEDS="10177 10181" BLIND_SEEDS="1193 1201"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = probe ]; then
  cd $W
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7214 --hand-drawn 1 --hand-variety 1 \
    --json > $OUT/probe_base.json 2> $OUT/probe_base.err &
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7214 --hand-drawn 1 --hand-variety 1 \
    $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
  wait; exit
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3093 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3093 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
