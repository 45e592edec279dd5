#!/usr/bin/env bash
# The authors' Placing environment under a fixed policy (authors_placing_env.py says what and why):
#
#   bash benches/reference/run_authors_placing_env.sh FORK [EPISODES] [SEED] [uniform|closed|sb3]
#
# (sb3: STEPS=15000 in the environment sets how long it learns; EPISODES is unused.)
# FORK: a clone or bare git directory of misoshiruseijin/robosuite (nothing in it is written).
# Its robosuite sources (BallBasket, BasketHoopObject and the rest of the fork) are exported at
# its HEAD into an overlay folder beside the venv; files the snapshot lacks (large meshes and
# textures) are taken from PyPI's robosuite 1.4.1, the release the fork migrated to. MuJoCo 2.3.7
# and numpy < 2: the versions robosuite 1.4.1 runs with (MuJoCo 3+ refuses the Sawyer's meshes,
# numpy 2 its transform utilities). The venv and the overlay live under ~/.cache/dualrep and are
# made only when missing; nothing of the fork is committed here.
set -euo pipefail
FORK=${1:?usage: run_authors_placing_env.sh FORK [EPISODES] [SEED] [uniform|closed|sb3]}
EPISODES=${2:-200}
SEED=${3:-0}
POLICY=${4:-uniform}
cd "$(dirname "$0")/../.."
VENV="${VENV:-$HOME/.cache/dualrep/venv-robosuite}"
OVERLAY="${OVERLAY:-$HOME/.cache/dualrep/robosuite-fork-overlay}"
if ! "$VENV/bin/python" -c 'import torch, stable_baselines3, mujoco, numba, robosuite' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check robosuite==1.4.1 "mujoco==2.3.7" "numpy<2" \
    stable-baselines3==2.9.2 torch==2.15.0 gymnasium==1.4.0
fi
if [ ! -f "$OVERLAY/robosuite/environments/manipulation/ball_basket.py" ]; then
  git_dir=$(git -C "$FORK" rev-parse --absolute-git-dir)
  tmp="$OVERLAY.tmp"
  rm -rf "$tmp"
  mkdir -p "$tmp"
  # One file at a time: a snapshot may lack some blobs, which `git archive` would refuse.
  git --git-dir "$git_dir" ls-tree -r HEAD robosuite | while read -r _mode type oid path; do
    [ "$type" = blob ] || continue
    mkdir -p "$tmp/$(dirname "$path")"
    GIT_NO_LAZY_FETCH=1 git --git-dir "$git_dir" cat-file blob "$oid" >"$tmp/$path" 2>/dev/null || rm -f "$tmp/$path"
  done
  site=$("$VENV/bin/python" -c 'import os, robosuite; print(os.path.dirname(robosuite.__file__))' 2>/dev/null)
  (cd "$site" && find . -type f ! -name '*.pyc' | while read -r f; do
    [ -s "$tmp/robosuite/$f" ] || { mkdir -p "$tmp/robosuite/$(dirname "$f")"; cp "$f" "$tmp/robosuite/$f"; }
  done)
  echo "overlay from $(git --git-dir "$git_dir" rev-parse --short HEAD) of the fork" >"$tmp/FORK_COMMIT"
  mv "$tmp" "$OVERLAY"
fi
cd /tmp  # robosuite writes a macros warning, nothing else, relative to the working directory
exec "$VENV/bin/python" "$OLDPWD/benches/reference/authors_placing_env.py" --overlay "$OVERLAY" \
  --episodes "$EPISODES" --seed "$SEED" --policy "$POLICY" --steps "${STEPS:-15000}"
