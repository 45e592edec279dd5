#!/usr/bin/env bash
# At equal answers, count or placement? (docs/results/lunar-critic-judge/README.md, its last
# section, written before the runs): EF-100 normed's seed 2 critics kept every 2k steps to 20k
# (EARLY: a folder of `train --keep-checkpoints` checkpoints), each judged on DREF normed's seed 2
# policy at its kept checkpoints (DREF: the row's checkpoints folder), as the section's table was:
# 50 episodes from seed 1000, 8 actions around each step's. Summaries go to OUT as
# e<EF-100 step>-on-<DREF step>.json; the table is printed by judge_table.py.
#
#   bash benches/grids/judge_equal_answers.sh BINARY EARLY DREF OUT
set -euo pipefail
bin=$1 early=$2 dref=$3 out=$4
mkdir -p "$out"
source "$(dirname "$0")/judge_run.sh"
judge() {  # judge EF-100-checkpoint DREF-checkpoint
  local e=$1 d=$2
  local es ds
  es=$(basename "$e" .run | sed 's/^step-0*//')
  ds=$(basename "$d" .run | sed 's/^step-0*//')
  judge_into "$out/e$es-on-$ds.json" --checkpoint "$d" --critic-from "$e"
}
# The reading's two equal-count points first, then the curve on the latest DREF checkpoint, then
# the equal-count critics on the other two.
pick() { ls "$1"/step-*.run | awk -v s="$2" -F'step-' '{ n = $2 + 0; d = n - s; if (d < 0) d = -d; if (best == "" || d < bd) { best = $0; bd = d } } END { print best }'; }
judge "$(pick "$early" 8000)" "$(pick "$dref" 40000)"
judge "$(pick "$early" 10000)" "$(pick "$dref" 80000)"
for e in "$early"/step-*.run; do judge "$e" "$(pick "$dref" 80000)"; done
for s in 50000 70000; do
  judge "$(pick "$early" 8000)" "$(pick "$dref" "$s")"
  judge "$(pick "$early" 10000)" "$(pick "$dref" "$s")"
done
judge "$(pick "$early" 10000)" "$(pick "$dref" 40000)"
judge "$(pick "$early" 8000)" "$(pick "$dref" 80000)"
