#!/bin/bash
# round vision37's tuning probe (no rule yet): the verifier's rescue may also keep an X or triangle refused by its
# shape confidence alone (confidence_rescue); configs x tuning seeds 7091-7094, two at a time, in a worktree of the
# code ($W). Table: vision36d_probe_table.py $OUT base,CR 7091,7092 7093,7094
W=${W:-/tmp/s64/wtp}; export W PYTHONPATH=$W  # the worktree's code, not the editable install's
export OUT=${OUT:-/tmp/s64/v37/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-base CR}; do
  for s in 7091 7092; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7093 7094; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [CR]="--set confidence_rescue=1" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
