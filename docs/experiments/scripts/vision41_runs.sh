#!/bin/bash
# round vision41's rule runs (docs/experiments/rules/vision41_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's code ($W); STAGE s1, heldout, blind or gates; "speed" runs vision36c_speed.py.
# Table: vision36d_rule_table.py $OUT 7127,7128 8837,7541 461,463
export V="filled_solidity=0.9 filled_fill=0.82"
export W=${W:-/tmp/s74/w41} OUT=${OUT:-/tmp/s74/v41/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7127 7128" HELDOUT_SEEDS="8837 7541" BLIND_SEEDS="461 463"
if [ "$1" = speed ]; then
  mkdir -p $OUT && cd $W && PYTHONPATH=. exec .venv/bin/python docs/experiments/scripts/vision36c_speed.py 8837 400 5 "$V"
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
