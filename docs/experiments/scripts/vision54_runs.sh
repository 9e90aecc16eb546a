#!/bin/bash
# round vision54's rule runs (docs/experiments/rules/vision54_rule.txt), base and variant, in a worktree of the rule's
# code ($W): STAGE heldout or blind (vision36_runs.sh). Table: vision36d_rule_table.py $OUT - 10111,10133
# 1103,1109,1117,1129; pool (e) with round vision53's blind counts by hand, as the rule says.
export V="propose_open_margin=0.5"
export W=${W:-/tmp/s103/wt54} OUT=${OUT:-/tmp/s103/v54/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export HELDOUT_SEEDS="10111 10133" BLIND_SEEDS="1103 1109 1117 1129"
mkdir -p $OUT
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
