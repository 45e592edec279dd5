#!/usr/bin/env bash
# Commits each grid run the moment local_runs.sh copies it into the results (its summary.json is
# copied last), one commit a run, naming the run's figures and the binary that made it: a session
# can stop at any time, and a run finished but not committed is lost with its machine.
#
#   nohup setsid bash benches/grids/commit_results.sh FOLDER BINARY >> LOG 2>&1 < /dev/null &
#
# FOLDER: a folder of rows under docs/results, each `<row>/seed<N>/`, e.g.
# docs/results/dref-ablation/short-opening-layer-norm/lunar-lander. BINARY: the grid's binary, whose
# name ends in its commit (dualrep-<8 hex digits>). Runs whose summary.json was there when it
# started are left alone; it commits only their folder (`git commit -- <run>`), so work in the
# tree beside it is not swept in. Stop it with `pkill -f commit_results.sh`.
set -euo pipefail
cd "$(dirname "$0")/../.."
folder=${1:?the results folder of rows}
binary=${2:?the grid binary (dualrep-<commit>)}
commit=${binary##*dualrep-}
declare -A seen
for summary in "$folder"/*/seed*/summary.json; do
  [ -e "$summary" ] && seen[$summary]=1
done
echo "$(date -u +%FT%TZ) watching $folder (${#seen[@]} runs there already), binary $commit"
while true; do
  for summary in "$folder"/*/seed*/summary.json; do
    [ -e "$summary" ] || continue
    [ -n "${seen[$summary]:-}" ] && continue
    sleep 5 # local_runs.sh copies summary.json last; let the copy finish
    while [ -e .git/index.lock ]; do sleep 2; done
    run=$(dirname "$summary")
    figures=$(python3 - "$summary" "$commit" <<'PY'
import json
import sys

s = json.load(open(sys.argv[1]))
last10 = round(s["final_success_rate"] * 10)
threads = s.get("threads", 1)
print(
    f"{s['cumulative_return'] / 1000:.1f}k at {100 * s['feedback_fraction']:.2f} %, last 10: "
    f"{last10} succeed, mean return {s['final_mean_return']:.1f}; {s['kernels']} kernels on "
    f"{threads} thread{'s' if threads != 1 else ''}, {s['wall_seconds']:,.0f} s, "
    f"binary {sys.argv[2]}"
)
PY
)
    # A run that cannot be committed is said in the log and left staged; the watcher goes on.
    if git add -- "$run" && git commit -q -m "results: ${run#docs/results/} (${figures})" -- "$run"; then
      echo "$(date -u +%FT%TZ) committed $(git log --oneline -1)"
    else
      echo "$(date -u +%FT%TZ) could not commit $run: commit it by hand"
    fi
    seen[$summary]=1
  done
  sleep 20
done
