#!/bin/bash
# round vision39's tuning probe: a second, softer binarisation (soft_offset 6, or 8: *o8) of the pyramid's half level
# (S2), of the full-resolution level (S1) or of both (S12), configs x tuning seeds 7106-7109, two at a time, in a
# worktree of the code ($W). Table: vision36d_probe_table.py $OUT base,S2,S1,S12 7106,7107 7108,7109
W=${W:-/tmp/s65/wt}; export W PYTHONPATH=$W  # the worktree's code, not the editable install's
export OUT=${OUT:-/tmp/s65/v39/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-base S2 S1 S12}; do
  for s in 7106 7107; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7108 7109; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [S2]="--set soft_levels=2" [S1]="--set soft_levels=1" [S12]="--set soft_levels=1,2"
    [S1o8]="--set soft_levels=1 --set soft_offset=8" [S12o8]="--set soft_levels=1,2 --set soft_offset=8" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
