#!/usr/bin/env bash
# stable-baselines3's SAC on Gymnasium's LunarLanderContinuous-v3 with our configuration, 20k
# steps per seed, into docs/results/lunar-lander-sb3/seed<S>/ (seeds skipped once they have a
# summary.json). Packages go into a venv of their own, created only when missing.
#   bash benches/reference/run_sb3_lunar_lander.sh 0 1 2
set -euo pipefail
cd "$(dirname "$0")/../.."
VENV="$HOME/.cache/dualrep/venv-sb3"
if ! "$VENV/bin/python" -c 'import stable_baselines3, gymnasium, Box2D, torch' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check \
    stable-baselines3==2.9.2 "gymnasium[box2d]==1.4.0" torch==2.15.0
fi
export OMP_NUM_THREADS=1
for seed in "${@:-0 1 2}"; do
  out="docs/results/lunar-lander-sb3/seed$seed"
  [ -f "$out/summary.json" ] && continue
  "$VENV/bin/python" benches/reference/sb3_lunar_lander.py --steps "${STEPS:-20000}" --seed "$seed" --out "$out"
done
