#!/usr/bin/env bash
# The refits of docs/results/lunar-critic-judge/README.md ("The same answers fitted again"), in
# the order they ran: DREF normed's seed 2 policy at 80,152 and 40,101 steps judged by fresh heads
# fitted 20,000 steps to DREF normed's own answers (rd-*) and to EF-100 normed's first answers, as
# many (re-*, from the 2k-20k probe's checkpoint at 10,434 steps), and R_D at 80,152 again with
# refit seed 1; then the other three with refit seed 1. Skips a summary already written.
#
#   bash benches/grids/refit_critics.sh BINARY DREF-CHECKPOINTS EARLY-EF100-CHECKPOINTS OUT
set -euo pipefail
bin=$1 dref=$2 early=$3 out=$4
mkdir -p "$out"
source "$(dirname "$0")/judge_run.sh"
judge() {  # judge OUT-NAME SIM-ARGUMENTS...
  local name=$1
  shift
  judge_into "$out/$name" "$@"
}
judge rd-80152-s0.json --checkpoint "$dref/step-000080152.run" --refit-critic 20000
judge re-80152-s0.json --checkpoint "$dref/step-000080152.run" \
  --critic-from "$early/step-000010434.run" --refit-critic 20000 --refit-answers 10006
judge rd-40101-s0.json --checkpoint "$dref/step-000040101.run" --refit-critic 20000
judge re-40101-s0.json --checkpoint "$dref/step-000040101.run" \
  --critic-from "$early/step-000010434.run" --refit-critic 20000 --refit-answers 8004
judge rd-80152-s1.json --checkpoint "$dref/step-000080152.run" --refit-critic 20000 --refit-seed 1
# Added at 01:12 UTC, after the seed 1 check above came out at 0.060: the other three with refit
# seed 1, so that each point has two refits.
judge re-80152-s1.json --checkpoint "$dref/step-000080152.run" \
  --critic-from "$early/step-000010434.run" --refit-critic 20000 --refit-answers 10006 --refit-seed 1
judge rd-40101-s1.json --checkpoint "$dref/step-000040101.run" --refit-critic 20000 --refit-seed 1
judge re-40101-s1.json --checkpoint "$dref/step-000040101.run" \
  --critic-from "$early/step-000010434.run" --refit-critic 20000 --refit-answers 8004 --refit-seed 1
