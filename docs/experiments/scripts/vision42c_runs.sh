#!/bin/bash
# round vision42c's rule runs (docs/experiments/rules/vision42c_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's code ($W); STAGE s1, heldout, blind or gates.
# Table: vision36d_rule_table.py $OUT 7146,7147 5987,9431 509,577
export V="propose_sure=0,0.6,0 propose_sure_thresholds=0.3,0.85,0.9"
export W=${W:-/tmp/s75/w42} OUT=${OUT:-/tmp/s75/v42c/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7146 7147" HELDOUT_SEEDS="5987 9431" BLIND_SEEDS="509 577"
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
