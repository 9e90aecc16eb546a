#!/bin/bash
# round vision59's recordings (spent seeds, before its rule; vision59_rule.txt): max_contrast_ratio=0.8 on round vision56's
# tuning and blind seeds; the base runs are round vision56's variant (today's default).
cd /tmp/s104/wt
export PYTHONPATH=/tmp/s104/wt
S="--set max_contrast_ratio=0.8"
run() { .venv/bin/python bench/vision_bench.py "$@" --json; }
run --split tuning --frames 1000 --seed 7206 $S > /tmp/s104/d59/t7206.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7206 --hand-drawn 0.5 $S > /tmp/s104/d59/t7206h.json 2>/dev/null
wait
run --split tuning --frames 1000 --seed 7207 $S > /tmp/s104/d59/t7207.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7207 --hand-drawn 0.5 $S > /tmp/s104/d59/t7207h.json 2>/dev/null
wait
run --split blind --frames 2000 --seed 1163 $S > /tmp/s104/d59/b1163.json 2>/dev/null &
run --split blind --frames 2000 --seed 1171 $S > /tmp/s104/d59/b1171.json 2>/dev/null
wait; date > /tmp/s104/d59/done
