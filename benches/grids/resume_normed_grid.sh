#!/usr/bin/env bash
# Starts (or resumes) the normed learner's Lunar Lander grid on this machine, from the repository
# alone if need be: the queue of lunar_layer_norm_queue.py (the rows, each seed's cuts at 60k
# after its pair, DREF normed until 60k on the other seeds, then SAC alone normed) run by
# local_runs.sh from a copy of the release binary outside target/: on a machine of fewer than 4
# cores one run at a time on all of them (on the 2-core AVX2 EPYC, 1,900-2,090 steps a minute
# over a 150k run, 72-79 min, where two side by side on one thread each made 630-690: a run
# ends inside a session, and a machine lost between sessions loses at most the run in progress),
# else two at a time on one thread each. Runs already in docs/results are skipped; runs stopped
# midway resume from their checkpoints under the grid folder's scratch/, if it survived. Beside
# the runner it starts commit_results.sh, which commits each run the moment it lands (unless one
# is running already).
#
#   bash benches/grids/resume_normed_grid.sh [GRID]      # GRID: /work/grid by default
#
# The binary must know `train --branch-from FOLDER` (eaa0da9c or later; training unchanged since
# cab5e144): the newest in GRID/bin named by its commit that does is used, else one is built and
# copied there.
set -euo pipefail
cd "$(dirname "$0")/../.."
grid=${1:-/work/grid}
if pgrep -f 'local_runs.sh' > /dev/null; then
  echo "a grid runner is already running:" >&2
  pgrep -af 'local_runs.sh' >&2
  exit 1
fi
mkdir -p "$grid/bin" "$grid/scratch"
bin=""
# Only binaries named by their commit (dualrep-<8 hex digits>): the grid's record names the commit
# it ran, so a binary built from a tree that is no commit (a work in progress) is never picked.
for candidate in $(ls -t "$grid"/bin/dualrep-* 2> /dev/null); do
  [[ $(basename "$candidate") =~ ^dualrep-[0-9a-f]{8}$ ]] || continue
  if "$candidate" train --help | grep -q 'given a folder of kept ones'; then
    bin=$candidate
    break
  fi
done
if [ -z "$bin" ]; then
  cargo build --release
  bin="$grid/bin/dualrep-$(git rev-parse --short=8 HEAD)"
  cp target/release/dualrep "$bin"
fi
python3 benches/grids/lunar_layer_norm_queue.py > "$grid/ln-queue.jobs"
parallel=2 threads=1
if [ "$(nproc)" -lt 4 ]; then parallel=1 threads=$(nproc); fi
nohup setsid bash benches/grids/local_runs.sh "$bin" "$grid/ln-queue.jobs" "$grid/scratch" \
  docs/results "$parallel" "$threads" >> "$grid/ln-rows.log" 2>&1 < /dev/null &
echo "started: $bin on $grid/ln-queue.jobs ($(grep -cv '^\s*\(#\|$\)' "$grid/ln-queue.jobs") lines); log $grid/ln-rows.log"
# Each finished run committed as it lands (a session can stop at any time), unless a watcher runs.
if ! pgrep -f 'commit_results.sh' > /dev/null; then
  nohup setsid bash benches/grids/commit_results.sh \
    docs/results/dref-ablation/short-opening-layer-norm/lunar-lander "$bin" \
    >> "$grid/commits.log" 2>&1 < /dev/null &
  echo "committing each run as it lands; log $grid/commits.log"
fi
