#!/bin/bash
# round vision65b's rule runs (docs/experiments/rules/vision65b_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (round vision47's round-things probe, seed 14,
# 150 frames a kind; the crossing probe, seed 86, 200 frames a mode; and bench/vision_bench.py, tuning seed 7246, 1,000
# frames, every mark drawn by hand and every finger varied) or "clips" (bench/vision_clips.py, seed 3169).
# Table: vision36d_rule_table.py $OUT 7244,7245 10303,10309 1301,1303
export V="x_solidity=0.6 x_solidity_veto=0"
export W=${W:-/tmp/s112/wt65b} OUT=${OUT:-/tmp/s112/v65b/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7244 7245" HELDOUT_SEEDS="10303 10309" BLIND_SEEDS="1301 1303"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = probe ]; then
  cd $W
  (.venv/bin/python docs/experiments/scripts/vision47_round_probe.py 14 150 "base" "var $V" > $OUT/round_probe.txt 2>&1
   .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 86 > $OUT/cross_base.txt 2>&1
   .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 86 $SETS \
     > $OUT/cross_var.txt 2>&1) &
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7246 --hand-drawn 1 --hand-variety 1 \
    --json > $OUT/probe_base.json 2> $OUT/probe_base.err
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7246 --hand-drawn 1 --hand-variety 1 \
    $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
  wait; exit
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3169 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3169 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
