#!/bin/bash
# round vision42b's tuning probe: a proposed O with a strong heatmap peak kept at a lower verifier bar than 0.99
# (`propose_sure` O, `propose_sure_thresholds` O), on tuning 7140 + 7141 drawn half by hand and 7142 + 7143 exact; the
# peaks and bars were read off round vision42's recording (vision42_proposals.py) of tuning 7132 + 7133, where the
# proposed O under 0.99 with a peak of 0.6 or more and 0.7 or more from the verifier were 10 true marks and no false one.
# PO6: peak 0.6, bar 0.75; PO6b: 0.6, 0.85; PO5: 0.5, 0.8. vision_probe.sh does the runs.
# Table: vision36d_probe_table.py $OUT base,PO6,PO6b,PO5 7140,7141 7142,7143
export W=${W:-/tmp/s75/w42} OUT=${OUT:-/tmp/s75/p42b}
export CONFIGS=${CONFIGS:-"base;PO6 propose_sure=0,0.6,0 propose_sure_thresholds=0.3,0.75,0.9;\
PO6b propose_sure=0,0.6,0 propose_sure_thresholds=0.3,0.85,0.9;PO5 propose_sure=0,0.5,0 propose_sure_thresholds=0.3,0.8,0.9"}
export HAND_SEEDS="7140 7141" EXACT_SEEDS="7142 7143"
exec bash "$(dirname "$0")/vision_probe.sh"
