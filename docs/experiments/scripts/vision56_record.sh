#!/bin/bash
# round vision56's recordings (vision56_rule.txt, "Recorded"): propose_sure=0.7,0.6,0 on spent tuning and blind seeds, in a
# worktree of round vision54's landing (0b03def); the base runs are round vision55's (tuning, the same code) and round
# vision54's variant (blind), both today's default.
cd /tmp/s103/wt55
export PYTHONPATH=/tmp/s103/wt55
S="--set propose_sure=0.7,0.6,0"
run() { .venv/bin/python bench/vision_bench.py "$@" --json; }
run --split tuning --frames 1000 --seed 7203 $S > /tmp/s103/d56/t7203.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7203 --hand-drawn 0.5 $S > /tmp/s103/d56/t7203h.json 2>/dev/null
wait
run --split tuning --frames 1000 --seed 7204 $S > /tmp/s103/d56/t7204.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7204 --hand-drawn 0.5 $S > /tmp/s103/d56/t7204h.json 2>/dev/null
wait
run --split blind --frames 2000 --seed 1103 $S > /tmp/s103/d56/b1103.json 2>/dev/null &
run --split blind --frames 2000 --seed 1109 $S > /tmp/s103/d56/b1109.json 2>/dev/null
wait; date > /tmp/s103/d56/done
