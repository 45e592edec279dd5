#!/usr/bin/env bash
# The grids of the two DREF issues, in the order they are wanted, resumable: each `reproduce`
# skips finished runs and a stopped `train` resumes from its checkpoint. Two lanes, one run each
# at a time on one thread; run from a copy of the release binary outside target/:
#
#   nohup bash benches/grids/dref_grids.sh /work/grid/bin/dualrep-<commit> /work/grid > /work/grid/lanes.log 2>&1 &
#
# then copy finished runs (config.json, metrics.csv, summary.json) into docs/results/ as the
# READMEs there say. Lane A: the product's DREF and what it is compared with on Reaching and
# Placing (docs/results/fig3), then its ablation (docs/dref.md); lane B: Placing's product DREF,
# then the as-run grid (docs/results/fig3-as-run), then Lunar Lander at 150k.
set -euo pipefail
bin=${1:?the dualrep binary}
out=${2:?the scratch folder}
run() { nice -n 10 "$bin" --threads 1 reproduce fig3 --jobs 1 "$@"; }

lane_a() {
  run --tasks reaching --seeds 10 --methods dref,ef-dref --out "$out/fig3"
  # Reaching's stalls under the product rule (docs/results/fig3/README.md): its rule without
  # the mask, and the authors' rule with it.
  run --tasks reaching --seeds 10 --methods dref --set human_critic_mask=false --out "$out/ablation-unmasked"
  run --tasks reaching --seeds 10 --methods dref-masked --out "$out/fig3"
  # Seeds 5-9 of the rows reused from the committed 5 seeds (copy those into "$out/fig3" first).
  run --tasks reaching,placing --seeds 10 --methods ef-100,sac,dref-authors --out "$out/fig3"
  run --tasks placing --seeds 10 --methods dref-masked --out "$out/fig3"
  run --tasks placing --seeds 10 --methods dref-authors --set rank_window=1000 --out "$out/ablation-window"
  run --tasks placing --seeds 10 --methods dref-authors --set max_feedback_rate=0.05 --out "$out/ablation-ceiling"
  # The ceiling's level (docs/results/dref-ablation/README.md: Placing seed 1 learns at 10 %).
  run --tasks placing --seeds 10 --methods dref --set max_feedback_rate=0.1 --out "$out/ablation-ceiling-10"
}

lane_b() {
  run --tasks placing --seeds 10 --methods dref,ef-dref --out "$out/fig3"
  run --tasks reaching,placing --seeds 10 --methods dref-authors,ef-100,sac,ef-dref-authors \
    --set profile=as-run --out "$out/as-run"
  run --tasks lunar-lander --seeds 5 --methods dref,ef-dref --out "$out/fig3-lunar-lander-150k"
  run --tasks lunar-lander --seeds 5 --methods dref-authors,ef-100,ef-dref-authors \
    --set profile=as-run --out "$out/as-run"
}

lane_a > "$out/lane-a.log" 2>&1 &
lane_b > "$out/lane-b.log" 2>&1 &
wait
