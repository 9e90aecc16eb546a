#!/bin/bash
# round vision36's rule runs (docs/experiments/rules/vision36_rule.txt), base and variant, two at a time, in a worktree
# of the rule's commit ($W). STAGE: s1 (tuning), heldout, blind or gates.
W=${W:-/tmp/s62/wt}; export W
export OUT=${OUT:-/tmp/s62/v36/rule}; mkdir -p $OUT
export V=${V:-"card_rescue_from=band,texture,ink,ratio,letter"}  # settings, space-separated
SETS=""; for v in $V; do SETS="$SETS --set $v"; done; export SETS
S1_SEEDS=${S1_SEEDS:-"7076 7077"} HELDOUT_SEEDS=${HELDOUT_SEEDS:-"3719 6143"} BLIND_SEEDS=${BLIND_SEEDS:-"359 367"}
jobs_list=()
case "$1" in
  s1) for c in base var; do for s in $S1_SEEDS; do jobs_list+=("$c|$s|tuning|"); jobs_list+=("$c|$s|tuning|--hand-drawn 0.5"); done; done ;;
  heldout) for c in base var; do for s in $HELDOUT_SEEDS; do jobs_list+=("$c|$s|heldout|"); done; done ;;
  blind) for c in base var; do for s in $BLIND_SEEDS; do jobs_list+=("$c|$s|blind|"); done; done ;;
esac
run() {
  IFS='|' read c s split extra <<< "$1"
  set_="" ; [ "$c" = var ] && set_="$SETS"
  tag=${c}_${split}_${s}; [ -n "$extra" ] && tag=${tag}_hand
  frames=2000; [ "$split" = tuning ] && frames=1000
  cd $W && .venv/bin/python bench/vision_bench.py --split $split --frames $frames --seed $s $extra $set_ --json \
    > $OUT/$tag.json 2> $OUT/$tag.err
}
export -f run
if [ "$1" = gates ]; then
  cd $W
  PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision19_scene_gate.py $SETS > $OUT/gate_var.txt 2>&1
  for c in base var; do
    set_=""; [ "$c" = var ] && set_="$SETS"
    .venv/bin/python bench/vision_words.py --seed 555 $set_ > $OUT/words_$c.txt 2>&1
  done
  PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py > $OUT/arrow_base.txt 2>&1
  PYTHONPATH=. .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py $V > $OUT/arrow_var.txt 2>&1
  exit
fi
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
