#!/usr/bin/env bash
# Runs a list of `dualrep train` runs side by side until a deadline, for a many-core machine
# lent for minutes (the device of docs/results/dref-ablation/README.md: 16 cores, one call at
# most 10 minutes): only runs that finish are worth the call, so each gets what is left of the
# deadline and is killed at it; the finished runs' config.json, metrics.csv, summary.json and
# stderr.log come back in one tarball, the unfinished ones are listed.
#
#   bash benches/grids/parallel_runs.sh BINARY JOBS DEADLINE_S OUT_TARBALL [PARALLEL]
#
# BINARY: dualrep (or an xz-compressed copy, `*.xz`, to travel light). JOBS: one run a line,
# `<grid dir>/<task>/<method>/seed<S> <train arguments...>`, e.g.
#   fig3/reaching/ef-100/seed5 --task reaching --method ef-100 --seed 5
# (the run gets `--steps 100000 --checkpoint-every 0 --threads 1 --out <scratch>/<dir>` unless the
# line sets `--steps`). The folders are laid out as `reproduce` lays out a grid, so the tarball
# unpacks into one and `reproduce --report-only` reads it. Lines run in order, PARALLEL (default:
# the cores) at a time: put the runs that matter most first.
set -u
bin=${1:?the dualrep binary}
jobs=${2:?the jobs file}
deadline=${3:?seconds}
tarball=${4:?the tarball to write}
parallel=${5:-$(nproc)}
t0=$(date +%s)
if [[ $bin == *.xz ]]; then
  xz -dc "$bin" > /tmp/dualrep-parallel && chmod +x /tmp/dualrep-parallel && bin=/tmp/dualrep-parallel
fi
scratch=$(mktemp -d)
echo "cpu: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, avx512f: $(grep -c -m1 avx512f /proc/cpuinfo)"
export bin scratch t0 deadline
one() {
  dir=$1
  shift
  left=$((deadline - ($(date +%s) - t0)))
  [ "$left" -gt 30 ] || exit 0
  steps=(--steps 100000)
  [[ " $* " == *" --steps "* ]] && steps=()
  mkdir -p "$scratch/$dir"
  timeout --signal=KILL "$left" "$bin" --threads 1 train "${steps[@]}" --checkpoint-every 0 \
    --out "$scratch/$dir" "$@" > "$scratch/$dir/stdout.log" 2> "$scratch/$dir/stderr.log"
  echo "$(($(date +%s) - t0)) s: rc $? $dir"
}
export -f one
grep -v '^\s*\(#\|$\)' "$jobs" | xargs -P "$parallel" -L 1 bash -c 'one "$@"' _
cd "$scratch" || exit 1
files=()
while read -r d; do
  if [ -e "$d/summary.json" ]; then
    files+=("$d/config.json" "$d/metrics.csv" "$d/summary.json" "$d/stderr.log")
  else
    echo "unfinished: $d ($(($(wc -l < "$d/metrics.csv" 2>/dev/null || echo 1) - 1)) episodes)"
  fi
done < <(find . -mindepth 4 -maxdepth 4 -type d -name 'seed*' | sed 's|^\./||' | sort)
if [ ${#files[@]} -gt 0 ]; then
  tar czf "$tarball" "${files[@]}"
fi
echo "$((${#files[@]} / 4)) finished runs in $tarball, $(($(date +%s) - t0)) s"
