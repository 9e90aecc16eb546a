#!/bin/bash
# round vision55's recordings (vision55_rule.txt, "Recorded"): hand_triangle_loose=0.8 on spent tuning and blind seeds, in a
# worktree of round vision54's landing (0b03def); the base runs are round vision53's variant (tuning: the same code and
# settings) and round vision54's variant (blind). The solid=1 variant: the same with --set hand_triangle_solid=1.
cd /tmp/s103/wt55
export PYTHONPATH=/tmp/s103/wt55
S="--set hand_triangle_loose=0.8"
run() { .venv/bin/python bench/vision_bench.py "$@" --json; }
run --split tuning --frames 1000 --seed 7200 --hand-drawn 0.5 $S > /tmp/s103/d55/t7200h.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7201 --hand-drawn 0.5 $S > /tmp/s103/d55/t7201h.json 2>/dev/null
wait
run --split blind --frames 2000 --seed 1103 $S > /tmp/s103/d55/b1103.json 2>/dev/null &
run --split blind --frames 2000 --seed 1109 $S > /tmp/s103/d55/b1109.json 2>/dev/null
wait; date > /tmp/s103/d55/done
