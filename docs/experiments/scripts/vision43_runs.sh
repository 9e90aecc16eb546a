#!/bin/bash
# round vision43's rule runs (docs/experiments/rules/vision43_rule.txt): vision36_runs.sh with its seeds and variant
# (the proposer retrained with --arrows --everyday, read from $MODEL through `proposer_model`), in a worktree of the
# rule's code ($W); STAGE s1, heldout, blind or gates.
# Table: vision36d_rule_table.py $OUT 7148,7149 3571,6263 593,599
export MODEL=${MODEL:-/tmp/s76/p43/proposer.onnx}
export V="proposer_model=$MODEL"
export W=${W:-/tmp/s76/w43} OUT=${OUT:-/tmp/s76/v43/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7148 7149" HELDOUT_SEEDS="3571 6263" BLIND_SEEDS="593 599"
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
