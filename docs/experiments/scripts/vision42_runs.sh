#!/bin/bash
# round vision42's rule runs (docs/experiments/rules/vision42_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's code ($W); STAGE s1, heldout, blind or gates.
# Table: vision36d_rule_table.py $OUT 7138,7139 8837,7541 461,463
export V="propose_sure=0.7,0,0 propose_sure_thresholds=0.01,0.99,0.9"
export W=${W:-/tmp/s75/w42} OUT=${OUT:-/tmp/s75/v42/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7138 7139" HELDOUT_SEEDS="8837 7541" BLIND_SEEDS="461 463"
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
