#!/bin/bash
# round vision35's tuning probe: configs x tuning seeds, two at a time, in a worktree of the candidate code ($W)
W=${W:-/tmp/s61/wt}; export W
export OUT=${OUT:-/tmp/s61/v35/probe}; mkdir -p $OUT
jobs_list=()
for c in base A B C D; do
  for s in 7053 7054; do jobs_list+=("$c|$s|--hand-drawn 0.5"); done
  for s in 7055 7056; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [A]="--set hand_triangle_loose=0.9" [B]="--set hand_triangle_loose=0.9 --set hand_triangle_floor=0.1"
                   [C]="--set hand_triangle_loose=0.95 --set hand_triangle_floor=0.1" [D]="--set hand_triangle_loose=0.8" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
