#!/bin/bash
# round vision40's tuning probe: the second network retrained on only what it is asked about (`training
# --claimed-kept TRIANGLE`, written to $MODEL), judged at the default 0.8 (C8) and at 0.9 (C9) against today's
# (base), and the same trained for 24 epochs instead of 6 ($MODEL24) at 0.9 (D9), on tuning 7116 + 7117 drawn half by
# hand and 7118 + 7119 exact. vision_probe.sh does the runs.
# Table: vision36d_probe_table.py $OUT base,C8,C9,D9 7116,7117 7118,7119
MODEL=${MODEL:-/tmp/s66/v40/spec.onnx} MODEL24=${MODEL24:-/tmp/s66/v40/spec_e24.onnx}
export W=${W:-/tmp/s66/w40} OUT=${OUT:-/tmp/s66/v40/probe}
export CONFIGS=${CONFIGS:-"base;C8 hand_triangle_model=$MODEL;C9 hand_triangle_model=$MODEL hand_triangle=0.9;\
D9 hand_triangle_model=$MODEL24 hand_triangle=0.9"}
export HAND_SEEDS="7116 7117" EXACT_SEEDS="7118 7119"
exec bash "$(dirname "$0")/vision_probe.sh"
