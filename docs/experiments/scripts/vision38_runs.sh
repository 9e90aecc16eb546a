#!/bin/bash
# round vision38's rule runs (docs/experiments/rules/vision38_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's commit ($W); STAGE s1, heldout, blind or gates; "speed" runs vision36c_speed.py.
export V="propose_thresholds=0.3,0.99,0.7"
export W=${W:-/tmp/s64/wt38} OUT=${OUT:-/tmp/s64/v38/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7102 7103" HELDOUT_SEEDS="3061 5413" BLIND_SEEDS="449 457"
if [ "$1" = speed ]; then
  mkdir -p $OUT && cd $W && PYTHONPATH=. exec .venv/bin/python docs/experiments/scripts/vision36c_speed.py 3061 400 5 "$V"
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
