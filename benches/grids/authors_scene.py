#!/usr/bin/env python3
"""Placing's SAC and EF-100 on the authors' scene (`hoop = "ring"`, `release_at = 0.92`, as run)
beside the same seeds on tasks.md's scene: the table and tests of
docs/results/fig3-as-run/placing-sac/README.md, "Their scene in ours", from the committed runs.

    python3 benches/grids/authors_scene.py [docs/results/fig3-as-run]

Prints the per-seed table (markdown), each row's mean +- s.e. and how many runs learn, the exact
one-sided Mann-Whitney test that SAC on their scene lies above SAC on ours, the count of runs
with a success within 15k steps against the authors' environment (one-sided Fisher exact),
SAC / EF-100 on their scene (s.e. by the delta method), and the authors' SAC in true sums above
ours. The authors' figures below were decoded from their tfevents by
benches/reference/authors_runs.py and their env by authors_placing_env.py (the README's items).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from curves import episodes  # noqa: E402
from rows import exact_p_above, learns, mean_se, runs  # noqa: E402

# The authors' Placing SAC, 7 logged runs, cumulative true sums (100 a success).
AUTHORS_SAC_TRUE_SUMS = [79.0e3, 0.1e3, 118.8e3, 55.7e3, 0.1e3, 63.8e3, 12.2e3]
# Runs with a success within 15k steps on the authors' environment: theirs and ours of it.
AUTHORS_ENV_EARLY = (5, 9)
# The authors' all-runs SAC / EF-100 on Placing (docs/results/authors-runs/).
AUTHORS_RATIO = (0.46, 0.21)
EARLY_STEPS = 15_000


def first_success(seed_dir: Path) -> int | None:
    return next((int(e["step"]) for e in episodes(seed_dir) if e["outcome"] == "success"), None)


def fisher_greater(a: int, n1: int, c: int, n2: int) -> float:
    """P(X >= a) for the first group's successes when a + c successes fall at random among
    n1 + n2 runs (hypergeometric): that the first group's share is above the second's."""
    total, hits = n1 + n2, a + c
    denominator = math.comb(total, hits)
    return sum(
        math.comb(n1, k) * math.comb(n2, hits - k)
        for k in range(a, min(n1, hits) + 1)
    ) / denominator


def by_seed(folder: Path) -> dict[int, dict]:
    return {r["seed"]: r for r in runs(folder)}


def k(value: float) -> str:
    return f"{value / 1000:.1f}k"


def summary(rows: dict[int, dict]) -> str:
    values = [r["cumulative_return"] for r in rows.values()]
    mean, se = mean_se(values)
    learnt = sum(learns(r) for r in rows.values())
    return f"{k(mean)} ± {k(se)} ({len(values)}, {learnt} learn)"


def main() -> None:
    root = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/results/fig3-as-run")
    sac_ring = by_seed(root / "placing-sac/sac-authors-scene")
    ef_ring = by_seed(root / "placing-sac/ef-100-authors-scene")
    sac_box = by_seed(root / "placing/sac")
    ef_box = by_seed(root / "placing/ef-100")
    print(
        "| seed | SAC, their scene | last 10 | first success (steps) | SAC, tasks.md's scene "
        "(`../placing/sac/`) | EF-100, their scene | EF-100, tasks.md's scene |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|")
    early = 0
    for seed in sorted(set(sac_ring) | set(ef_ring)):
        cells = []
        if seed in sac_ring:
            run = sac_ring[seed]
            first = first_success(root / f"placing-sac/sac-authors-scene/seed{seed}")
            early += first is not None and first <= EARLY_STEPS
            cells += [
                k(run["cumulative_return"]),
                str(run["last10"]),
                f"{first:,}" if first is not None else "none in 100k",
            ]
        else:
            cells += ["–", "", ""]
        cells.append(k(sac_box[seed]["cumulative_return"]) if seed in sac_box else "–")
        if seed in ef_ring:
            placed = first_success(root / f"placing-sac/ef-100-authors-scene/seed{seed}")
            no_success = "" if placed is not None else " (no success)"
            cells.append(k(ef_ring[seed]["cumulative_return"]) + no_success)
        else:
            cells.append("–")
        cells.append(k(ef_box[seed]["cumulative_return"]) if seed in ef_box else "–")
        print(f"| {seed} | " + " | ".join(cells) + " |")
    print(
        f"| mean ± s.e. | **{summary(sac_ring)}** | | | {summary(sac_box)} | "
        f"**{summary(ef_ring)}** | {summary(ef_box)} |"
    )
    print()
    sac_ring_values = [r["cumulative_return"] for r in sac_ring.values()]
    sac_box_values = [r["cumulative_return"] for r in sac_box.values()]
    u, p = exact_p_above(sac_ring_values, sac_box_values)
    print(
        f"SAC, their scene above tasks.md's: U = {u:g} of "
        f"{len(sac_ring_values) * len(sac_box_values)}, one-sided exact p = {p:.3f}"
    )
    theirs, their_runs = AUTHORS_ENV_EARLY
    p_early = fisher_greater(theirs, their_runs, early, len(sac_ring))
    print(
        f"runs with a success within {EARLY_STEPS:,} steps: {early} of {len(sac_ring)}, "
        f"the authors' environment {theirs} of {their_runs}: one-sided Fisher exact p = "
        f"{p_early:.2f}"
    )
    sac_mean, sac_se = mean_se(sac_ring_values)
    ef_mean, ef_se = mean_se([r["cumulative_return"] for r in ef_ring.values()])
    ratio = sac_mean / ef_mean
    ratio_se = abs(ratio) * math.sqrt((sac_se / sac_mean) ** 2 + (ef_se / ef_mean) ** 2)
    within = abs(ratio - AUTHORS_RATIO[0]) <= AUTHORS_RATIO[1]
    print(
        f"SAC / EF-100, their scene: {ratio:.2f} ± {ratio_se:.2f} (the authors' all-runs "
        f"{AUTHORS_RATIO[0]:.2f} ± {AUTHORS_RATIO[1]:.2f}: "
        f"{'within' if within else 'not within'} one s.e.)"
    )
    mean, se = mean_se(AUTHORS_SAC_TRUE_SUMS)
    u, p = exact_p_above(AUTHORS_SAC_TRUE_SUMS, sac_ring_values)
    print(
        f"the authors' SAC in true sums {k(mean)} ± {k(se)} ({len(AUTHORS_SAC_TRUE_SUMS)} runs) "
        f"above ours on their scene: U = {u:g} of "
        f"{len(AUTHORS_SAC_TRUE_SUMS) * len(sac_ring_values)}, p = {p:.3f}"
    )


if __name__ == "__main__":
    main()
