#!/bin/bash
# round vision39b's tuning probe: a proposed triangle the verifier gives 0.7 to 0.9 kept where a ring round its box,
# 0.15 (R15) or 0.1 (R10) of its size wide, is clear paper (propose_ring), on tuning seeds 7112-7115, in a worktree of
# 7a63020 ($W). Table: vision36d_probe_table.py $OUT base,R15,R10 7112,7113 7114,7115. (Run in this script's first
# form, commit 5a1923f, which did the same in a copy of the loop `vision_probe.sh` now holds.)
W=${W:-/tmp/s65/wt} OUT=${OUT:-/tmp/s65/v39b/probe} HAND_SEEDS="7112 7113" EXACT_SEEDS="7114 7115" \
  CONFIGS=${CONFIGS:-"base;R15 propose_ring=0.15;R10 propose_ring=0.1"} \
  exec bash "$(dirname "$0")/vision_probe.sh"
