#!/bin/bash
# round vision35b's tuning probe: configs x tuning seeds, two at a time, in a worktree of the candidate code ($W)
W=${W:-/tmp/s61/wt}; export W
export OUT=${OUT:-/tmp/s61/v35b/probe}; mkdir -p $OUT
jobs_list=()
for c in base E F G; do
  for s in 7059 7060; do jobs_list+=("$c|$s|--hand-drawn 0.5"); done
  for s in 7061 7062; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [E]="--set hand_triangle_loose=0.8" [F]="--set hand_triangle_loose=0.8 --set hand_triangle_solid=0.7"
                   [G]="--set hand_triangle_loose=0.9" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
