#!/bin/bash
# round vision39c's tuning probe: a proposed triangle the verifier gives at least 0.7 (D7), 0.5 (D5) or 0.3 (D3), under
# its 0.9, kept where it lies over a doubted triangle (a component the shape and context tests read as a triangle,
# which the verifier refused: propose_doubted), on tuning seeds 7112-7115 (the base runs are round vision39b's), in a
# worktree of a330649 ($W). Table: vision36d_probe_table.py $OUT base,D7,D5,D3 7112,7113 7114,7115. (Run in this
# script's first form, commit 5a1923f, which did the same in a copy of the loop `vision_probe.sh` now holds.)
W=${W:-/tmp/s65/wt} OUT=${OUT:-/tmp/s65/v39b/probe} HAND_SEEDS="7112 7113" EXACT_SEEDS="7114 7115" \
  CONFIGS=${CONFIGS:-"D7 propose_doubted=0.7;D5 propose_doubted=0.5;D3 propose_doubted=0.3"} \
  exec bash "$(dirname "$0")/vision_probe.sh"
