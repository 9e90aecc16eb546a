#!/bin/bash
# round vision36d's tuning probe (no rule yet): with letter_card, the mark's card only the light region of about its
# paper's grey (letter_card_paper 0.15-0.35); configs x tuning seeds 7085-7088, two at a time, in a worktree of the code
# ($W). Table: vision36d_probe_table.py $OUT base,P25,P35
W=${W:-/tmp/s63/wtp}; export W
export OUT=${OUT:-/tmp/s63/v36d/probe}; mkdir -p $OUT
jobs_list=()
for c in ${CONFIGS:-base P25 P35}; do
  for s in 7085 7086; do jobs_list+=("$c|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in 7087 7088; do jobs_list+=("$c|$s|"); done
done
run() {
  IFS='|' read c s extra <<< "$1"
  declare -A CFG=( [base]="" [P25]="--set letter_card_paper=0.25" [P35]="--set letter_card_paper=0.35" [P15]="--set letter_card_paper=0.15" )
  cd $W && .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json \
    > $OUT/${c}_$s.json 2> $OUT/${c}_$s.err
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
