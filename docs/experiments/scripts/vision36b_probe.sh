#!/bin/bash
# round vision36b's tuning probe: the rescue may overrule a letter-test refusal with no neighbour in the mark's ink ("beside")
# at three measures of "the same ink" (CONFIGS="C CB25": on the mark's card; both); configs x tuning seeds, two at a time, in a worktree of the code ($W)
W=${W:-/tmp/s62/wt}; export W
export OUT=${OUT:-/tmp/s62/v36b/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-B15 B25 B40}; do
  for s in 7071 7072; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7073 7074; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [B15]="--set letter_other_ink=0.15 --set card_rescue_from=band,texture,ink,ratio,beside"
                   [B25]="--set letter_other_ink=0.25 --set card_rescue_from=band,texture,ink,ratio,beside"
                   [B40]="--set letter_other_ink=0.4 --set card_rescue_from=band,texture,ink,ratio,beside"
                   [C]="--set letter_card=1 --set card_rescue_from=band,texture,ink,ratio,beside"
                   [CB25]="--set letter_card=1 --set letter_other_ink=0.25 --set card_rescue_from=band,texture,ink,ratio,beside" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
