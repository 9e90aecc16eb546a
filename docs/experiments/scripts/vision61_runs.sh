#!/bin/bash
# round vision61's rule runs (docs/experiments/rules/vision61_rule.txt), base and variant, two at a time, in a worktree
# of the rule's code ($W): STAGE s1 (tuning, --without filled_triangle), probe, gates, heldout, blind or clips.
export V="filled_paper_round=0.9"
export W=${W:-/tmp/s106/wt61} OUT=${OUT:-/tmp/s106/v61/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
mkdir -p $OUT
SETS=""; for v in $V; do SETS="$SETS --set $v"; done; export SETS
WITHOUT="--without filled_triangle"; export WITHOUT
cd $W
case "$1" in
  s1)
    jobs_list=()
    for c in base var; do for s in 7218 7219; do jobs_list+=("$c|$s|"); jobs_list+=("$c|$s|--hand-drawn 0.5"); done; done
    run() {
      IFS='|' read c s extra <<< "$1"
      set_=""; [ "$c" = var ] && set_="$SETS"
      tag=${c}_tuning_${s}; [ -n "$extra" ] && tag=${tag}_hand
      .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed $s $extra $WITHOUT $set_ --json \
        > $OUT/$tag.json 2> $OUT/$tag.err
    }
    export -f run
    printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"' ;;
  probe)
    .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7220 --hand-drawn 1 --hand-variety 1 \
      $WITHOUT --json > $OUT/probe_base.json 2> $OUT/probe_base.err &
    .venv/bin/python bench/vision_bench.py --split tuning --frames 1000 --seed 7220 --hand-drawn 1 --hand-variety 1 \
      $WITHOUT $SETS --json > $OUT/probe_var.json 2> $OUT/probe_var.err
    wait ;;
  gates)
    .venv/bin/python docs/experiments/scripts/vision19_scene_gate.py $SETS > $OUT/gate_var.txt 2>&1 &
    .venv/bin/python bench/vision_words.py --seed 555 > $OUT/words_base.txt 2>&1
    wait
    .venv/bin/python bench/vision_words.py --seed 555 $SETS > $OUT/words_var.txt 2>&1 &
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py > $OUT/arrow_base.txt 2>&1
    wait
    .venv/bin/python docs/experiments/scripts/vision34_triclutter_probe.py $V > $OUT/arrow_var.txt 2>&1 ;;
  heldout|blind)
    [ "$1" = heldout ] && seeds="10211 10223" || seeds="1223 1229"
    for s in $seeds; do
      .venv/bin/python bench/vision_bench.py --split $1 --frames 2000 --seed $s --json > $OUT/base_$1_$s.json 2> $OUT/base_$1_$s.err &
      .venv/bin/python bench/vision_bench.py --split $1 --frames 2000 --seed $s $SETS --json > $OUT/var_$1_$s.json 2> $OUT/var_$1_$s.err
      wait
    done ;;
  clips)
    .venv/bin/python bench/vision_clips.py --clips 100 --seed 3109 > $OUT/clips_base.txt 2>&1 &
    .venv/bin/python bench/vision_clips.py --clips 100 --seed 3109 $SETS > $OUT/clips_var.txt 2>&1
    wait ;;
esac
echo done $1
