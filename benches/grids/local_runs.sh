#!/usr/bin/env bash
# Runs a list of `dualrep train` runs on this machine, PARALLEL at a time, straight into the
# committed results: a run whose summary.json is already under RESULTS is skipped, a run stopped
# midway resumes from its checkpoint under SCRATCH, and a finished run's config.json,
# metrics.csv and summary.json are copied to RESULTS/<dir> at once (commit them as they come).
# A new machine starts where the repository is: nothing but RESULTS is needed to resume.
#
#   nohup bash benches/grids/local_runs.sh BINARY JOBS SCRATCH RESULTS [PARALLEL [THREADS]] > LOG 2>&1 &
#
# BINARY: a copy of the release binary outside target/ (the grids' rule). JOBS: one run a line,
# `<dir under RESULTS> <train arguments...>`, e.g.
#   dref-ablation/ablation-window/placing/dref-authors/seed4 --task placing --method dref-authors --seed 4 --set rank_window=1000
# (100,000 steps unless the line sets `--steps`). Lines start in order: put the runs that matter
# most first. THREADS (1 unless given) is each run's `--threads`: results do not depend on it
# (core's a_run_is_the_same_bits_on_avx512_and_avx2_and_on_any_number_of_threads), so one run at
# a time on both cores of a 2-core machine finishes a run in a session where two side by side
# would not.
set -u
bin=${1:?the dualrep binary}
jobs=${2:?the jobs file}
scratch=${3:?the scratch folder}
results=${4:?the results folder (docs/results)}
parallel=${5:-2}
threads=${6:-1}
echo "cpu: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, avx512f: $(grep -c -m1 avx512f /proc/cpuinfo)"
echo "binary: $bin ($(sha256sum "$bin" | cut -c1-12)), $parallel at a time, $threads threads each"
export bin scratch results threads
# `nice` orders processes only inside their autogroup, and a runner started under setsid has one
# of its own, so without this the grid takes its full share of the cores from a build or test
# beside it whatever its nice; the autogroup's nice is what the scheduler weighs between them.
echo 10 > "/proc/$$/autogroup" 2> /dev/null || echo "autogroup nice not set: $(cat "/proc/$$/autogroup" 2> /dev/null)"
one() {
  dir=$1
  shift
  [ -e "$results/$dir/summary.json" ] && exit 0
  steps=(--steps 100000)
  [[ " $* " == *" --steps "* ]] && steps=()
  mkdir -p "$scratch/$dir"
  # A branch whose source checkpoint is gone (a new machine, where SCRATCH did not survive) and
  # that has no checkpoint of its own runs from step 0 instead: `train --branch-from` writes the
  # rows, curves and summary that the same arguments run from step 0 write (tests/train_branch.rs),
  # so only the time differs. Said in the log, so the record shows which way it ran.
  local args=("$@") i
  for i in "${!args[@]}"; do
    if [ "${args[$i]}" = --branch-from ] && [ ! -e "${args[$((i + 1))]}" ] \
      && [ ! -e "$scratch/$dir/checkpoint.run" ]; then
      echo "$(date -u +%FT%TZ) $dir: ${args[$((i + 1))]} is gone; run from step 0"
      args=("${args[@]:0:$i}" "${args[@]:$((i + 2))}")
      break
    fi
  done
  set -- "${args[@]}"
  t0=$(date +%s)
  nice -n 10 "$bin" --threads "$threads" train "${steps[@]}" --out "$scratch/$dir" "$@" \
    >> "$scratch/$dir/stdout.log" 2>> "$scratch/$dir/stderr.log"
  rc=$?
  if [ $rc -eq 0 ] && [ -e "$scratch/$dir/summary.json" ]; then
    mkdir -p "$results/$dir"
    cp "$scratch/$dir/config.json" "$scratch/$dir/metrics.csv" "$results/$dir/"
    # The learner's curves, where the binary writes them (7b894c2c or later).
    [ -e "$scratch/$dir/learner.csv" ] && cp "$scratch/$dir/learner.csv" "$results/$dir/"
    # The answers by sign, where the binary writes them (the twenty-seventh session's or later).
    [ -e "$scratch/$dir/answers.csv" ] && cp "$scratch/$dir/answers.csv" "$results/$dir/"
    # summary.json last: its presence marks the run finished.
    cp "$scratch/$dir/summary.json" "$results/$dir/"
  fi
  echo "$(date -u +%FT%TZ) rc $rc after $(($(date +%s) - t0)) s: $dir"
}
export -f one
grep -v '^\s*\(#\|$\)' "$jobs" | xargs -P "$parallel" -L 1 bash -c 'one "$@"' _
echo "$(date -u +%FT%TZ) all lines done"
