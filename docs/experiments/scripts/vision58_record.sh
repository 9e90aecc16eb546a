#!/bin/bash
# round vision58's recordings (spent seeds, no rule; the vision README): loose_confidence=0 and 0.3 on round vision56's
# tuning and blind seeds, in a worktree of this round's code; the base runs are round vision56's variant (today's default).
cd /tmp/s104/wt
export PYTHONPATH=/tmp/s104/wt
S="--set loose_confidence=0"
run() { .venv/bin/python bench/vision_bench.py "$@" --json; }
run --split tuning --frames 1000 --seed 7206 $S > /tmp/s104/d58b/t7206.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7206 --hand-drawn 0.5 $S > /tmp/s104/d58b/t7206h.json 2>/dev/null
wait
run --split tuning --frames 1000 --seed 7207 $S > /tmp/s104/d58b/t7207.json 2>/dev/null &
run --split tuning --frames 1000 --seed 7207 --hand-drawn 0.5 $S > /tmp/s104/d58b/t7207h.json 2>/dev/null
wait
run --split blind --frames 2000 --seed 1163 $S > /tmp/s104/d58b/b1163.json 2>/dev/null &
run --split blind --frames 2000 --seed 1171 $S > /tmp/s104/d58b/b1171.json 2>/dev/null
wait; date > /tmp/s104/d58b/done
for s in 1163 1171; do run --split blind --frames 2000 --seed $s --set loose_confidence=0.3 > /tmp/s104/d58b/b${s}_03.json 2>/dev/null & done; wait
