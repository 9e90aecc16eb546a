#!/bin/bash
# round vision36b's rule runs (docs/experiments/rules/vision36b_rule.txt): vision36_runs.sh with its seeds and variant
export V="letter_card=1 letter_other_ink=0.25 card_rescue_from=band,texture,ink,ratio,beside"
export OUT=${OUT:-/tmp/s62/v36b/rule}
export S1_SEEDS="7078 7079" HELDOUT_SEEDS="4657 8761" BLIND_SEEDS="389 397"
exec bash "$(dirname "$0")/vision36_runs.sh" "$@"
