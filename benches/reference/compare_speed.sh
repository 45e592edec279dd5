#!/usr/bin/env bash
# Our training speed beside its peers, measured in one run on this machine (Lunar Lander's
# sizes), printing each JSON line and the ratios:
#   1. one SAC update with the human critic: `dualrep bench sac` against PyTorch
#      (torch_sac_update.py), one thread each;
#   2. a whole run end to end: `dualrep bench train` (DREF, and SAC) against stable-baselines3's
#      SAC on Gymnasium's LunarLanderContinuous-v3 (sb3_train.py), ours on one thread and on the
#      default (both cores, at most 2), SB3 on one.
# Peers and ours alternate, twice, so that a disturbance on a shared machine hits both.
#   bash benches/reference/compare_speed.sh [STEPS]     (DUALREP_KERNELS picks our kernels)
# Packages go into a venv of their own, created only when missing (the one
# run_sb3_lunar_lander.sh uses).
set -euo pipefail
cd "$(dirname "$0")/../.."
STEPS=${1:-2000}
VENV="$HOME/.cache/dualrep/venv-sb3"
if ! "$VENV/bin/python" -c 'import stable_baselines3, gymnasium, Box2D, torch' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet --disable-pip-version-check \
    stable-baselines3==2.9.2 "gymnasium[box2d]==1.4.0" torch==2.15.0
fi
export OMP_NUM_THREADS=1
cargo build --release --quiet
BIN=target/release/dualrep
[ -n "${CARGO_TARGET_DIR:-}" ] && BIN="$CARGO_TARGET_DIR/release/dualrep"
PY="$VENV/bin/python"
log=$(mktemp)
for round in 1 2; do
  "$BIN" bench sac --task lunar-lander --seconds 5 | tee -a "$log"
  "$PY" benches/reference/torch_sac_update.py --seconds 5 | tee -a "$log"
  "$BIN" bench train --task lunar-lander --steps "$STEPS" --threads 1 | tee -a "$log"
  "$BIN" bench train --task lunar-lander --steps "$STEPS" | tee -a "$log"
  "$BIN" bench train --task lunar-lander --method sac --steps "$STEPS" --threads 1 | tee -a "$log"
  (cd benches/reference && "../../$PY" sb3_train.py --steps "$STEPS") | tee -a "$log"
done
"$PY" - "$log" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
ours = [r for r in rows if "mflop_per_update" in r]
torch = [r for r in rows if r.get("framework", "").startswith("torch")]
sb3 = max(r["env_steps_per_second"] for r in rows if r.get("framework", "").startswith("stable"))
best = max(ours, key=lambda r: r["updates_per_second"])
ups = max(r["updates_per_second"] for r in torch)
print(f"update ({best['kernels']}, {best['threads']} thread): ours {best['updates_per_second']:.1f}/s = "
      f"{best['gflops']:.0f} GFLOP/s, {best['fraction_of_fma_peak']:.0%} of the FMA peak "
      f"({best['fma_peak_gflops']:.0f}); PyTorch {ups:.1f}/s: {best['updates_per_second'] / ups:.2f}x")
runs = {}
for r in rows:
    if "kernels" in r and "env_steps_per_second" in r:
        key = (r["method"], r["threads"], r["kernels"])
        runs[key] = max(runs.get(key, 0.0), r["env_steps_per_second"])
for (method, threads, kernels), got in sorted(runs.items()):
    print(f"train {method} ({kernels}, {threads} thread(s)): ours {got:.1f} env steps/s, "
          f"stable-baselines3 SAC (1 thread) {sb3:.1f}: {got / sb3:.2f}x")
PY
rm -f "$log"
