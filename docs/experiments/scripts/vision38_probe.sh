#!/bin/bash
# round vision38's tuning probe: the proposer's triangles kept at a lower verifier probability (propose_thresholds'
# TRIANGLE 0.9 -> 0.7: PT7; -> 0.8: PT8, run after the others with CONFIGS=PT8) and proposals from a lower heatmap
# peak (propose 0.3 -> 0.2: PP2); configs x tuning seeds 7098-7101, two at a time, in a worktree of the code ($W).
# Table: vision36d_probe_table.py $OUT base,PT7,PT8,PP2 7098,7099 7100,7101
W=${W:-/tmp/s64/wtp}; export W PYTHONPATH=$W  # the worktree's code, not the editable install's
export OUT=${OUT:-/tmp/s64/v38/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-base PT7 PP2}; do
  for s in 7098 7099; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7100 7101; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [PT7]="--set propose_thresholds=0.3,0.99,0.7" [PT8]="--set propose_thresholds=0.3,0.99,0.8"
    [PP2]="--set propose=0.2" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
