#!/usr/bin/env bash
# Lunar Lander steps per second: Gymnasium's Box2D version against our rapier2d port, measured
# back to back on this machine, one thread each, random actions. Prints one JSON line.
#   pip install "gymnasium[box2d]"; bash benches/reference/compare_lunar_lander.sh
set -euo pipefail
cd "$(dirname "$0")/../.."

gym=$(python3 benches/reference/gym_lunar_lander.py --policy random --episodes 300 --seed 0 |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["steps_per_second"])')

# Criterion's middle throughput estimate, e.g. "thrpt:  [47.3 Kelem/s 49.8 Kelem/s 52.3 Kelem/s]".
bench=$(cargo bench --quiet --bench env_steps -- lunar-lander 2>/dev/null)
ours=$(echo "$bench" | awk '
    /thrpt:/ && !done { done = 1; v = $4; u = $5; gsub(/\[/, "", v)
               m = (u ~ /^K/) ? 1e3 : (u ~ /^M/) ? 1e6 : 1; printf "%.0f\n", v * m }')

python3 -c "import json; g, o = float('$gym'), float('$ours'); print(json.dumps({'gymnasium_box2d_steps_per_second': round(g), 'dualrep_rapier2d_steps_per_second': round(o), 'ratio': round(o / g, 2)}))"
