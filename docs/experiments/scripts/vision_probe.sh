#!/bin/bash
# A tuning probe of detector settings (since round vision39; the earlier rounds' probe scripts are copies of one
# shape): bench/vision_bench.py --split tuning --frames $FRAMES --json for every config x seed, two at a time, in a
# worktree of the code ($W, imported through PYTHONPATH, not the editable install's). Its table:
# vision36d_probe_table.py $OUT NAME,NAME,... HAND_SEEDS EXACT_SEEDS (comma-separated there).
#   CONFIGS      configs separated by ';', each a NAME and the settings --set takes, space-separated:
#                "base;S2 soft_levels=2;S12o8 soft_levels=1,2 soft_offset=8"
#   HAND_SEEDS   seeds drawn half by hand with varied hands (--hand-drawn 0.5 --hand-variety 0.5)
#   EXACT_SEEDS  seeds drawn exactly
#   W, OUT       the worktree and the folder for NAME_SEED.json / .err; FRAMES (default 1000)
export W=${W:?the worktree of the code to probe} PYTHONPATH=$W
export OUT=${OUT:?the folder for the results}; mkdir -p "$OUT"
export FRAMES=${FRAMES:-1000}
jobs_list=()
IFS=';' read -ra configs <<< "${CONFIGS:?configs, e.g. base;S2 soft_levels=2}"
for cfg in "${configs[@]}"; do
  for s in ${HAND_SEEDS:-}; do jobs_list+=("$cfg|$s|--hand-drawn 0.5 --hand-variety 0.5"); done
  for s in ${EXACT_SEEDS:-}; do jobs_list+=("$cfg|$s|"); done
done
run() {
  IFS='|' read -r cfg s extra <<< "$1"
  read -r name settings <<< "$cfg"
  sets=""; for v in $settings; do sets="$sets --set $v"; done
  cd "$W" && .venv/bin/python bench/vision_bench.py --split tuning --frames "$FRAMES" --seed "$s" $extra $sets --json \
    > "$OUT/${name}_$s.json" 2> "$OUT/${name}_$s.err"
}
export -f run
printf '%s\n' "${jobs_list[@]}" | xargs -P 2 -I{} bash -c 'run "{}"'
echo done
