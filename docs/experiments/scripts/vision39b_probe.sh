#!/bin/bash
# round vision39b's tuning probe: a proposed triangle the verifier gives 0.7 to 0.9 kept where a ring round its box,
# 0.15 (R15) or 0.1 (R10) of its size wide, is clear paper (propose_ring); configs x tuning seeds 7112-7115, two at a
# time, in a worktree of the code ($W). Table: vision36d_probe_table.py $OUT base,R15,R10 7112,7113 7114,7115
W=${W:-/tmp/s65/wt}; export W PYTHONPATH=$W  # the worktree's code, not the editable install's
export OUT=${OUT:-/tmp/s65/v39b/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-base R15 R10}; do
  for s in 7112 7113; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7114 7115; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [R15]="--set propose_ring=0.15" [R10]="--set propose_ring=0.1" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
