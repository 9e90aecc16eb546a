#!/bin/bash
# round vision51's rule runs (docs/experiments/rules/vision51_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (bench/vision_bench.py, tuning seed 7196, 1,000
# frames, every mark drawn by hand and every finger varied) or "clips" (bench/vision_clips.py, seed 3049).
# Table: vision36d_rule_table.py $OUT 7194,7195 9967,9973 1063,1069
export V="star_depth=0.1"  # star_spread 1.6, star_inner 0.33: the defaults
export W=${W:-/tmp/s101/wtr} OUT=${OUT:-/tmp/s101/v51/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7194 7195" HELDOUT_SEEDS="9967 9973" BLIND_SEEDS="1063 1069"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = probe ]; then
  cd $W
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7196 --hand-drawn 1 --hand-variety 1 \
    --json > $OUT/probe_base.json 2> $OUT/probe_base.err &
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7196 --hand-drawn 1 --hand-variety 1 \
    $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
  wait; exit
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3049 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3049 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
