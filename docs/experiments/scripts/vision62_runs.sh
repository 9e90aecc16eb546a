#!/usr/bin/env bash
# Round vision62's measurements of the deflicker option (docs/experiments/rules/vision62_rule.txt): spent seeds only.
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=${1:-/tmp/vision62}
mkdir -p "$out"
bench() { PYTHONPATH=. .venv/bin/python bench/vision_bench.py --frames 2000 "$@"; }
bench --seed 10177 --flicker 1.0 --flicker-wave pwm > "$out/h10177_pwm_off.txt"
bench --seed 10177 --flicker 1.0 --flicker-wave pwm --set deflicker=1 > "$out/h10177_pwm_on.txt"
bench --seed 10177 --flicker 1.0 --set deflicker=1 > "$out/h10177_sine_on.txt"
bench --seed 10177 --set deflicker=1 > "$out/h10177_clean_on.txt"
bench --seed 1193 --split blind --flicker 1.0 --set deflicker=1 > "$out/b1193_sine_on.txt"
bench --seed 1193 --split blind --set deflicker=1 > "$out/b1193_clean_on.txt"
# clips (stop 108, after the frames above)
PYTHONPATH=. .venv/bin/python bench/vision_clips.py --seed 2718 --flicker 1.0 > "$out/c2718_flicker_off.txt"
PYTHONPATH=. .venv/bin/python bench/vision_clips.py --seed 2718 --flicker 1.0 --set deflicker=1 > "$out/c2718_flicker_on.txt"
PYTHONPATH=. .venv/bin/python bench/vision_clips.py --seed 2718 > "$out/c2718_steady.txt"
