#!/bin/bash
# round vision36's tuning probe: which card-test refusals the verifier's rescue may also overrule; configs x tuning
# seeds, two at a time, in a worktree of the code ($W)
W=${W:-/tmp/s62/wt}; export W
export OUT=${OUT:-/tmp/s62/v36/probe}; mkdir -p $OUT
jobs_list=()
for c in base L LF; do
  for s in 7071 7072; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7073 7074; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [L]="--set card_rescue_from=band,texture,ink,ratio,letter"
                   [LF]="--set card_rescue_from=band,texture,ink,ratio,letter,faint" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
