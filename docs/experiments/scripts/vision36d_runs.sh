#!/bin/bash
# round vision36d's rule runs (docs/experiments/rules/vision36d_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's commit ($W); STAGE s1, heldout, blind or gates; "speed" runs vision36c_speed.py.
export V="letter_card_paper=0.25"
export W=${W:-/tmp/s64/wt} OUT=${OUT:-/tmp/s64/v36d/rule}
export S1_SEEDS="7089 7090" HELDOUT_SEEDS="3917 5119" BLIND_SEEDS="421 433"
if [ "$1" = speed ]; then
  mkdir -p $OUT && cd $W && PYTHONPATH=. exec .venv/bin/python docs/experiments/scripts/vision36c_speed.py 3917 400 5 "$V"
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
