#!/bin/bash
# (the record of the run: loose candidates were asked through a `hand_triangle_loose` setting that the landed code no longer has)
# round vision34's tuning probe: configs x tuning seeds, two at a time
cd /work/main
out=/tmp/s60/v34/probe; mkdir -p $out
declare -A CFG=( [base]="" [A]="--set hand_triangle=0.8" [B]="--set hand_triangle=0.5" [C]="--set hand_triangle=0.8 --set hand_triangle_loose=0.9" [D]="--set hand_triangle=0.5 --set hand_triangle_loose=0.9" [E]="--set hand_triangle=0.8 --set hand_triangle_loose=0.95" )
jobs_list=()
for c in base A B C D E; do
  for s in 7045 7046; do jobs_list+=("$c|$s|--hand-drawn 0.5"); done
  for s in 7047 7048; do jobs_list+=("$c|$s|"); done
done
run() { IFS='|' read c s extra <<< "$1"; declare -A CFG=( [base]="" [A]="--set hand_triangle=0.8" [B]="--set hand_triangle=0.5" [C]="--set hand_triangle=0.8 --set hand_triangle_loose=0.9" [D]="--set hand_triangle=0.5 --set hand_triangle_loose=0.9" [E]="--set hand_triangle=0.8 --set hand_triangle_loose=0.95" ); .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra ${CFG[$c]} --json > /tmp/s60/v34/probe/${c}_$s.json 2> /tmp/s60/v34/probe/${c}_$s.err; }
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
