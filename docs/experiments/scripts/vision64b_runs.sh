#!/bin/bash
# round vision64b's rule runs (docs/experiments/rules/vision64b_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE s1, heldout, blind, gates (vision36_runs.sh), "probe" (round vision47's round-things probe, seed 12,
# 150 frames a kind; and bench/vision_bench.py, tuning seed 7240, 1,000 frames, every mark drawn by hand and every
# finger varied) or "clips" (bench/vision_clips.py, seed 3137).
# Table: vision36d_rule_table.py $OUT 7238,7239 10271,10273 1283,1289
export V="faint_veto_contrast=1"
export W=${W:-/tmp/s111/wt64b} OUT=${OUT:-/tmp/s111/v64b/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7238 7239" HELDOUT_SEEDS="10271 10273" BLIND_SEEDS="1283 1289"
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done
if [ "$1" = probe ]; then
  cd $W
  .venv/bin/python docs/experiments/scripts/vision47_round_probe.py 12 150 "base" "var $V" > $OUT/round_probe.txt 2>&1 &
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7240 --hand-drawn 1 --hand-variety 1 \
    --json > $OUT/probe_base.json 2> $OUT/probe_base.err
  .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7240 --hand-drawn 1 --hand-variety 1 \
    $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
  wait; exit
fi
if [ "$1" = clips ]; then
  cd $W
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3137 > $OUT/clips_base.txt 2>&1 &
  .venv/bin/python bench/vision_clips.py --clips 100 --seed 3137 $SETS > $OUT/clips_var.txt 2>&1
  wait; exit
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
