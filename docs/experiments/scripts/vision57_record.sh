#!/bin/bash
# round vision57's recordings (vision57_rule.txt, "Recorded"): propose_sure_thresholds=0.01,0.85,0.05 on spent tuning and blind
# seeds, in a worktree of round vision56's landing (2968fe3); the base runs are round vision56's variant (today's default).
cd /tmp/s103/wt57
export PYTHONPATH=/tmp/s103/wt57
S="--set propose_sure_thresholds=0.01,0.85,0.05"
run() { .venv/bin/python bench/vision_bench.py "$@" --json; }
run --split tuning --frames 1000 --seed 7206 $S > /tmp/s103/d57/t7206.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7206 --hand-drawn 0.5 $S > /tmp/s103/d57/t7206h.json 2>/dev/null
wait
run --split tuning --frames 1000 --seed 7207 $S > /tmp/s103/d57/t7207.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7207 --hand-drawn 0.5 $S > /tmp/s103/d57/t7207h.json 2>/dev/null
wait
run --split blind --frames 2000 --seed 1163 $S > /tmp/s103/d57/b1163.json 2>/dev/null &
run --split blind --frames 2000 --seed 1171 $S > /tmp/s103/d57/b1171.json 2>/dev/null
wait; date > /tmp/s103/d57/done
