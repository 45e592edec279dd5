#!/usr/bin/env bash
# The figures of docs/results/speed/README.md, in one run on this machine: the SAC update
# (Lunar Lander's sizes, human critic) on every kernel path this CPU has at 1 and 2 threads
# beside PyTorch at 1 and 2 threads, then whole runs end to end (`bench train`, DREF and SAC)
# beside stable-baselines3's SAC. Every JSON line goes to stdout with the load average before
# it, so that a figure taken on a shared machine says what else ran.
#   [ROUNDS=2] bash docs/results/speed/measure.sh [STEPS] [SECONDS]   (ROUNDS: of the updates)
# Needs the release binary (CARGO_TARGET_DIR honoured) and the venv compare_speed.sh makes.
set -euo pipefail
cd "$(dirname "$0")/../../.."
STEPS=${1:-500}
SECONDS_EACH=${2:-4}
BIN=${CARGO_TARGET_DIR:-target}/release/dualrep
PY="$HOME/.cache/dualrep/venv-sb3/bin/python"
export OMP_NUM_THREADS=1
# The load averages, then runnable / all tasks at that moment.
load() { echo "# load $(cut -d' ' -f1-4 /proc/loadavg) before: $*"; }
run() { load "$*"; "$@"; }
grep -m1 'model name' /proc/cpuinfo | sed 's/^/# /'
echo "# CPUs $(grep -c ^processor /proc/cpuinfo); AVX-512F: $(grep -qw avx512f /proc/cpuinfo && echo yes || echo no)"
ROUNDS=${ROUNDS:-1}
for round in $(seq "$ROUNDS"); do for threads in 1 2; do
  run "$PY" benches/reference/torch_sac_update.py --seconds "$SECONDS_EACH" --threads "$threads"
  for kernels in avx512 avx2 portable; do
    run "$BIN" bench sac --task lunar-lander --seconds "$SECONDS_EACH" --kernels "$kernels" \
      --threads "$threads"
  done
done; done
for threads in 1 2; do
  (cd benches/reference && run "$PY" sb3_train.py --steps "$STEPS" --threads "$threads")
  run "$BIN" bench train --task lunar-lander --steps "$STEPS" --threads "$threads"
  run "$BIN" bench train --task lunar-lander --method sac --steps "$STEPS" --threads "$threads"
done
load end
