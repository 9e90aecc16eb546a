#!/bin/bash
# round vision73b's rule runs (docs/experiments/rules/vision73b_rule.txt), base or variant, in a worktree of the rule's
# code ($W). STAGE: s1, probe, gates, heldout, speed, blind or clips; WHO: base or var (s1 with base runs the
# card-words probe for both; probe and gates run both).
#   W=/tmp/s119/wt73b OUT=/tmp/s119/rule73b bash vision73b_runs.sh STAGE WHO
export W=${W:-/tmp/s119/wt73b} OUT=${OUT:-/tmp/s119/rule73b}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
mkdir -p $OUT; cd $W
V="text_twin=0.3"; SETS="--set $V"
who=${2:-base}; set_=""; [ "$who" = var ] && set_="$SETS"
bench() {  # TAG SPLIT SEED FRAMES [EXTRA...]
  local tag=$1 split=$2 seed=$3 frames=$4; shift 4
  .venv/bin/python bench/vision_bench.py --split $split --frames $frames --seed $seed "$@" $set_ --json \
    > $OUT/${who}_$tag.json 2> $OUT/${who}_$tag.err
}
case "$1" in
  s1) bench tuning_7284 tuning 7284 2000 & bench tuning_7284_hand tuning 7284 2000 --hand-drawn 0.5; wait
      if [ "$who" = base ]; then  # the card-words probe, both configs
        .venv/bin/python docs/experiments/scripts/vision73_card_words.py 5581 400 > $OUT/cards_base.txt 2>&1 &
        .venv/bin/python docs/experiments/scripts/vision73_card_words.py 5581 400 $V > $OUT/cards_var.txt 2>&1; wait
      fi ;;
  probe)
    (.venv/bin/python docs/experiments/scripts/vision47_round_probe.py 26 150 "base" "var $V" > $OUT/round_probe.txt 2>&1
     .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 98 > $OUT/cross_base.txt 2>&1
     .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 98 $SETS \
       > $OUT/cross_var.txt 2>&1) &
    who=base set_="" bench probe_7285 tuning 7285 1000 --hand-drawn 1 --hand-variety 1
    who=var set_="$SETS" bench probe_7285 tuning 7285 1000 --hand-drawn 1 --hand-variety 1
    wait ;;
  gates)
    .venv/bin/python docs/experiments/scripts/vision19_scene_gate.py $SETS > $OUT/gate_var.txt 2>&1
    for c in base var; do
      s=""; [ "$c" = var ] && s="$SETS"
      .venv/bin/python bench/vision_words.py --seed 555 $s > $OUT/words_$c.txt 2>&1
    done
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py > $OUT/arrow_base.txt 2>&1
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py $V > $OUT/arrow_var.txt 2>&1 ;;
  heldout) bench heldout_10387 heldout 10387 2000 & bench heldout_10389 heldout 10389 2000; wait ;;
  speed) for s in 10387 10389; do  # alone on the machine: base and variant interleaved in one process
           .venv/bin/python docs/experiments/scripts/vision71c_speed.py heldout $s 400 6 $V > $OUT/speed_$s.json 2> $OUT/speed_$s.err
         done ;;
  blind) bench blind_1351 blind 1351 2000 & bench blind_1353 blind 1353 2000; wait ;;
  clips) .venv/bin/python bench/vision_clips.py --clips 50 --seed 3201 $set_ > $OUT/${who}_clips.txt 2>&1 ;;
esac
