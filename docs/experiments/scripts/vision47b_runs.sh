#!/bin/bash
# round vision47b's rule runs (docs/experiments/rules/vision47b_rule.txt): vision47_runs.sh with this round's variant,
# tuning seeds and probe seed; STAGE s1, probe, gates, heldout, blind or clips.
# Table: vision36d_rule_table.py $OUT 7172,7173 6151,8429 787,821
export V="propose_sure=0,0.6,0 propose_sure_thresholds=0.01,0.95,0.05 propose_o_clear=0.05"
export OUT=${OUT:-/tmp/s98/v47b/rule} S1_SEEDS="7172 7173" PROBE_SEED=3
exec bash "$(dirname "$0")/vision47_runs.sh" "$@"
