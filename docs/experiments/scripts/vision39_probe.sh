#!/bin/bash
# round vision39's tuning probe: a second, softer binarisation (soft_offset 6, or 8: *o8) of the pyramid's half level
# (S2), of the full-resolution level (S1) or of both (S12), on tuning seeds 7106-7109, in a worktree of 2659d29 ($W).
# Table: vision36d_probe_table.py $OUT base,S2,S1,S12 7106,7107 7108,7109. (Run in this script's first form, commit
# 5a1923f, which did the same in a copy of the loop `vision_probe.sh` now holds.)
W=${W:-/tmp/s65/wt} OUT=${OUT:-/tmp/s65/v39/probe} HAND_SEEDS="7106 7107" EXACT_SEEDS="7108 7109" \
  CONFIGS=${CONFIGS:-"base;S2 soft_levels=2;S1 soft_levels=1;S12 soft_levels=1,2"} \
  exec bash "$(dirname "$0")/vision_probe.sh"
# the offset-8 variants, not run: "S1o8 soft_levels=1 soft_offset=8;S12o8 soft_levels=1,2 soft_offset=8"
