#!/bin/bash
# round vision72's rule runs (docs/experiments/rules/vision72_rule.txt), base or variant, in a worktree of the rule's
# code ($W). STAGE: s1, probe, gates, heldout, speed, blind or clips; WHO: base or var (probe and gates run both).
#   W=/tmp/s118/wt72 OUT=/tmp/s118/rule72 bash vision72_runs.sh STAGE WHO
export W=${W:-/tmp/s118/wt72} OUT=${OUT:-/tmp/s118/rule72}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
mkdir -p $OUT; cd $W
V="safe_texture_window=0.5"; SETS="--set $V"
who=${2:-base}; set_=""; [ "$who" = var ] && set_="$SETS"
bench() {  # TAG SPLIT SEED FRAMES [EXTRA...]
  local tag=$1 split=$2 seed=$3 frames=$4; shift 4
  .venv/bin/python bench/vision_bench.py --split $split --frames $frames --seed $seed "$@" $set_ --json \
    > $OUT/${who}_$tag.json 2> $OUT/${who}_$tag.err
}
case "$1" in
  s1) bench tuning_7276 tuning 7276 1000 & bench tuning_7276_hand tuning 7276 1000 --hand-drawn 0.5; wait
      bench tuning_7276_glare tuning 7276 1000 --glare 1 ;;
  probe)
    (.venv/bin/python docs/experiments/scripts/vision47_round_probe.py 24 150 "base" "var $V" > $OUT/round_probe.txt 2>&1
     .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 96 > $OUT/cross_base.txt 2>&1
     .venv/bin/python docs/experiments/scripts/vision44_crossing_probe.py --frames 200 --seed 96 $SETS \
       > $OUT/cross_var.txt 2>&1) &
    who=base set_="" bench probe_7277 tuning 7277 1000 --hand-drawn 1 --hand-variety 1
    who=var set_="$SETS" bench probe_7277 tuning 7277 1000 --hand-drawn 1 --hand-variety 1
    wait ;;
  gates)
    .venv/bin/python docs/experiments/scripts/vision19_scene_gate.py $SETS > $OUT/gate_var.txt 2>&1
    for c in base var; do
      s=""; [ "$c" = var ] && s="$SETS"
      .venv/bin/python bench/vision_words.py --seed 555 $s > $OUT/words_$c.txt 2>&1
    done
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py > $OUT/arrow_base.txt 2>&1
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py $V > $OUT/arrow_var.txt 2>&1 ;;
  heldout) for s in 10383 10385; do bench heldout_$s heldout $s 2000 & bench heldout_${s}_glare heldout $s 2000 --glare 1
             wait; done ;;
  speed) for s in 10383 10385; do  # alone on the machine: base and variant interleaved in one process
           .venv/bin/python docs/experiments/scripts/vision71c_speed.py heldout $s 400 6 $V > $OUT/speed_$s.json 2> $OUT/speed_$s.err
         done ;;
  blind) for s in 1347 1349; do bench blind_$s blind $s 2000 & bench blind_${s}_glare blind $s 2000 --glare 1
           wait; done ;;
  clips) .venv/bin/python bench/vision_clips.py --clips 50 --seed 3199 $set_ > $OUT/${who}_clips.txt 2>&1 &
         .venv/bin/python bench/vision_clips.py --clips 50 --seed 3199 --glare 1 $set_ > $OUT/${who}_clips_glare.txt 2>&1
         wait ;;
esac
