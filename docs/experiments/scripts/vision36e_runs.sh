#!/bin/bash
# round vision36e's rule runs (docs/experiments/rules/vision36e_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's commit ($W); STAGE s1, heldout, blind or gates; "speed" runs vision36c_speed.py.
export V="letter_card_paper=0.25"
export W=${W:-/tmp/s64/wte} OUT=${OUT:-/tmp/s64/v36e/rule}
export PYTHONPATH=$W  # the benches import the worktree's code, not the editable install's
export S1_SEEDS="7095 7096" HELDOUT_SEEDS="2777 6373" BLIND_SEEDS="439 443"
if [ "$1" = speed ]; then
  mkdir -p $OUT && cd $W && PYTHONPATH=. exec .venv/bin/python docs/experiments/scripts/vision36c_speed.py 2777 400 5 "$V"
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
