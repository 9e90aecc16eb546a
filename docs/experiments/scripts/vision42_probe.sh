#!/bin/bash
# round vision42's tuning probe: a proposal with a strong heatmap peak kept at a lower verifier bar
# (`propose_sure`, `propose_sure_thresholds`), on tuning 7134 + 7135 drawn half by hand and 7136 + 7137 exact; the
# peaks and bars were read off stop 75's recording of every proposal on tuning 7132 (half by hand) + 7133 (exact).
# PX7: peak 0.7, X 0.01; PX7b: peak 0.7, X 0.05; PX6: peak 0.6, X 0.01; PXT8: peak 0.8, X 0.01 and TRIANGLE 0.05;
# PX7T8 (run after the others, with CONFIGS="PX7T8 ..." once propose_sure took a peak per shape): X at 0.7, 0.01 and
# TRIANGLE at 0.8, 0.05.
# (The first four ran while propose_sure was one peak for every shape: the same settings as written here.)
# vision_probe.sh does the runs. Table: vision36d_probe_table.py $OUT base,PX7,PX7b,PX6,PXT8,PX7T8 7134,7135 7136,7137
export W=${W:-/tmp/s75/w42} OUT=${OUT:-/tmp/s75/p42}
export CONFIGS=${CONFIGS:-"base;PX7 propose_sure=0.7,0,0 propose_sure_thresholds=0.01,0.99,0.9;\
PX7b propose_sure=0.7,0,0 propose_sure_thresholds=0.05,0.99,0.9;PX6 propose_sure=0.6,0,0 propose_sure_thresholds=0.01,0.99,0.9;\
PXT8 propose_sure=0.8,0,0.8 propose_sure_thresholds=0.01,0.99,0.05"}
export HAND_SEEDS="7134 7135" EXACT_SEEDS="7136 7137"
exec bash "$(dirname "$0")/vision_probe.sh"
