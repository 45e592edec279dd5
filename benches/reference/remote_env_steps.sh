#!/usr/bin/env bash
# Env steps per second through the env protocol against in-process, in one run on this
# machine (one thread each, random actions, resets included): our rapier2d Lunar Lander
# in-process; Gymnasium's Box2D LunarLanderContinuous-v3 in-process (Python) and served by
# `python -m dualrep.env`; and an env that does nothing, served the same way (the protocol's own
# cost per step). Prints one JSON line.
#   DUALREP=target/release/dualrep bash benches/reference/remote_env_steps.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN="${DUALREP:-target/release/dualrep}"
VENV="${VENV:-$HOME/.cache/dualrep/venv-gymnasium-box2d}"
STEPS="${STEPS:-20000}"
if ! "$VENV/bin/python" -c 'import dualrep.env, gymnasium, Box2D' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check "gymnasium[box2d]==1.4.0" ./clients/python
fi
logs=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$logs"' EXIT
url_of() {  # url_of LOG: wait for the env server's "serving ... on URL" line
  for _ in $(seq 100); do
    grep -o 'tcp://[0-9.]*:[0-9]*' "$1" && return
    sleep 0.1
  done
  cat "$1" >&2; exit 1
}
"$VENV/bin/python" -m dualrep.env --port 0 --no-render --gym LunarLanderContinuous-v3 >"$logs/gym" 2>&1 &
(cd benches/reference && exec "$VENV/bin/python" -m dualrep.env --port 0 --no-render \
  --make null_env:NullEnv --id null --max-episode-steps 1000) >"$logs/null" 2>&1 &
gym_url=$(url_of "$logs/gym")
null_url=$(url_of "$logs/null")
gym_in_process=$("$VENV/bin/python" benches/reference/gym_lunar_lander.py --policy random --episodes 200 --seed 0 |
  "$VENV/bin/python" -c 'import json,sys; print(json.load(sys.stdin)["steps_per_second"])')
"$BIN" bench env --task lunar-lander --env-url "$gym_url" --null-url "$null_url" --steps "$STEPS" |
  "$VENV/bin/python" -c "
import json, sys
r = json.load(sys.stdin)
r['gymnasium_in_process_steps_per_second'] = $gym_in_process
r['gymnasium_in_process_microseconds_per_step'] = 1e6 / $gym_in_process
# What one step through the protocol adds to Gymnasium's own step.
r['protocol_microseconds_per_step'] = r['remote']['microseconds_per_step'] - 1e6 / $gym_in_process
print(json.dumps(r))"
