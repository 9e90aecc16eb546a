#!/bin/bash
# round vision41's tuning probe: the filled-triangle shape test's bars (`filled_solidity`, `filled_fill`; today 0.93 /
# 0.85) lowered to 0.9 / 0.82 (F90), 0.85 / 0.8 (F85) and 0.8 / 0.75 (F80), on tuning 7123 + 7124 drawn half by hand
# and 7125 + 7126 exact. vision_probe.sh does the runs.
# Table: vision36d_probe_table.py $OUT base,F90,F85,F80 7123,7124 7125,7126
export W=${W:-/tmp/s74/w41} OUT=${OUT:-/tmp/s74/p41}
export CONFIGS=${CONFIGS:-"base;F90 filled_solidity=0.9 filled_fill=0.82;F85 filled_solidity=0.85 filled_fill=0.8;\
F80 filled_solidity=0.8 filled_fill=0.75"}
export HAND_SEEDS="7123 7124" EXACT_SEEDS="7125 7126"
exec bash "$(dirname "$0")/vision_probe.sh"
