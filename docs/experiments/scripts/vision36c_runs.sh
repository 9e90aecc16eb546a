#!/bin/bash
# round vision36c's rule runs (docs/experiments/rules/vision36c_rule.txt): vision36_runs.sh with its seeds and variant,
# in a worktree of the rule's commit ($W); STAGE s1, heldout, blind or gates; "speed" runs vision36c_speed.py.
export V="letter_card=1 letter_other_ink=0.25 card_rescue_from=band,texture,ink,ratio,beside"
export W=${W:-/tmp/s63/wt} OUT=${OUT:-/tmp/s63/v36c/rule}
export S1_SEEDS="7081 7082" HELDOUT_SEEDS="3719 6143" BLIND_SEEDS="359 367"
if [ "$1" = speed ]; then
  mkdir -p $OUT && cd $W && PYTHONPATH=. exec .venv/bin/python docs/experiments/scripts/vision36c_speed.py 3719 400 5 "$V"
fi
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
