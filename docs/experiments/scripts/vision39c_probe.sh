#!/bin/bash
# round vision39c's tuning probe: a proposed triangle the verifier gives at least 0.7 (D7), 0.5 (D5) or 0.3 (D3), under
# its 0.9, kept where it lies over a doubted triangle (a component the shape and context tests read as a triangle, which
# the verifier refused: propose_doubted); configs x tuning seeds 7112-7115 (the base runs are round vision39b's), two
# at a time, in a worktree of the code ($W). Table: vision36d_probe_table.py $OUT base,D7,D5,D3 7112,7113 7114,7115
W=${W:-/tmp/s65/wt}; export W PYTHONPATH=$W  # the worktree's code, not the editable install's
export OUT=${OUT:-/tmp/s65/v39b/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-D7 D5 D3}; do
  for s in 7112 7113; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7114 7115; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [D7]="--set propose_doubted=0.7" [D5]="--set propose_doubted=0.5"
    [D3]="--set propose_doubted=0.3" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
