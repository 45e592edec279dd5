#!/usr/bin/env bash
# DREF, EF-100 and SAC on Gymnasium's own LunarLanderContinuous-v3 (Box2D, from PyPI) through
# the env protocol: `python -m dualrep.env` serves it, `dualrep train --task lunar-lander
# --env-url` trains on it (our Lunar Lander's scene graph, expert and settings), 20k steps.
# Runs go to docs/results/lunar-lander-gymnasium/<method>/seed<S>/, one at a time, seeds
# outermost; a run with a summary.json is skipped and a stopped one resumes from its
# checkpoint.run, so running this again carries the grid on.
#
#   DUALREP=/path/to/dualrep bash benches/reference/run_remote_lunar_lander.sh 0 1 2
#
# DUALREP: the binary (default target/release/dualrep; copy it outside target/ for a long
# grid). The Python side goes into its own venv, created only when missing.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN="${DUALREP:-target/release/dualrep}"
VENV="${VENV:-$HOME/.cache/dualrep/venv-gymnasium-box2d}"
OUT="${OUT:-docs/results/lunar-lander-gymnasium}"
STEPS="${STEPS:-20000}"
if ! "$VENV/bin/python" -c 'import dualrep.env, gymnasium, Box2D' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check "gymnasium[box2d]==1.4.0" ./clients/python
fi
for seed in "${@:-0 1 2}"; do
  for method in ${METHODS:-dref ef-100 sac}; do
    run="$OUT/$method/seed$seed"
    [ -f "$run/summary.json" ] && continue
    mkdir -p "$run"
    log="$run/env-server.log"
    "$VENV/bin/python" -m dualrep.env --gym LunarLanderContinuous-v3 --port 0 --no-render \
      --success dualrep.scenes:lunar_lander_success >"$log" 2>&1 &
    server=$!
    url=""
    for _ in $(seq 100); do
      url=$(grep -o 'tcp://[0-9.]*:[0-9]*' "$log" || true)
      [ -n "$url" ] && break
      sleep 0.1
    done
    [ -n "$url" ] || { echo "the env server did not start:"; cat "$log"; kill "$server"; exit 1; }
    echo "== $method seed $seed on $url"
    status=0
    "$BIN" train --task lunar-lander --env-url "$url" --method "$method" --steps "$STEPS" \
      --seed "$seed" --out "$run" 2>"$run/stderr.log" >"$run/stdout.log" || status=$?
    kill "$server" 2>/dev/null || true
    wait "$server" 2>/dev/null || true
    [ "$status" = 0 ] || { echo "$method seed $seed failed ($status); see $run/stderr.log"; exit "$status"; }
  done
done
