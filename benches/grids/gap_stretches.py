#!/usr/bin/env python3
"""Where a row's gap to its comparator builds: each seed's cumulative reward cut into stretches of
steps, the comparator's gain in each stretch less the row's, mean +- s.e. over the seeds both
rows have, and the row's own gain per stretch (docs/dref-lunar-lander.md, "Where Lunar Lander's gap
builds").

    python3 benches/grids/gap_stretches.py \
        docs/results/fig3-lunar-lander-150k/lunar-lander/dref \
        docs/results/fig3-lunar-lander-150k/lunar-lander/ef-100 [--stretch 30000] [--steps 150000]

Each folder holds `seed<N>/` runs with metrics.csv (one row per finished episode: its end step
and the run's cumulative reward so far). A run's sum at a cut is that of its last episode ended
at or before it, so an episode straddling a cut counts in the stretch it ends in. Only seeds
whose runs have both finished (summary.json) are read, so a grid still running adds nothing.
"""

from __future__ import annotations

import argparse
import csv
import statistics
from pathlib import Path

from rows import mean_se


def finished_seeds(row: Path) -> dict[int, Path]:
    return {
        int(run.name.removeprefix("seed")): run
        for run in row.glob("seed*")
        if (run / "summary.json").exists()
    }


def sums_at(run: Path, cuts: list[int]) -> list[float]:
    """The run's cumulative reward at each cut (0 before its first episode ends)."""
    with open(run / "metrics.csv") as f:
        ends = [(int(r["step"]), float(r["cumulative_return"])) for r in csv.DictReader(f)]
    sums = []
    for cut in cuts:
        done = [total for step, total in ends if step <= cut]
        sums.append(done[-1] if done else 0.0)
    return sums


def gains(run: Path, cuts: list[int]) -> list[float]:
    sums = sums_at(run, cuts)
    return [b - a for a, b in zip(sums, sums[1:])]


def in_thousands(values: list[float]) -> str:
    """Mean +- s.e. (rows.py's), in thousands; the mean alone for one seed."""
    mean, se = mean_se(values)
    return f"{mean / 1e3:.1f}k" if len(values) < 2 else f"{mean / 1e3:.1f}k +- {se / 1e3:.1f}k"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("row", type=Path, help="the row's folder of seed<N>/ runs")
    parser.add_argument("comparator", type=Path, help="the comparator's folder, e.g. ef-100")
    parser.add_argument("--stretch", type=int, default=30_000)
    parser.add_argument("--steps", type=int, default=150_000)
    args = parser.parse_args()
    cuts = list(range(0, args.steps + 1, args.stretch))
    row, comparator = finished_seeds(args.row), finished_seeds(args.comparator)
    seeds = sorted(row.keys() & comparator.keys())
    if not seeds:
        raise SystemExit(f"no seed has finished in both {args.row} and {args.comparator}")
    labels = [f"{a // 1000}-{b // 1000}k" for a, b in zip(cuts, cuts[1:])]
    print(f"seeds {seeds}; per seed, the row's gain per stretch | the comparator's")
    gaps: list[list[float]] = [[] for _ in labels]
    own: list[list[float]] = [[] for _ in labels]
    for seed in seeds:
        mine, theirs = gains(row[seed], cuts), gains(comparator[seed], cuts)
        print(
            f"  seed {seed}: "
            + " ".join(f"{g / 1e3:6.1f}k" for g in mine)
            + "  | "
            + " ".join(f"{g / 1e3:6.1f}k" for g in theirs)
        )
        for i, (a, b) in enumerate(zip(mine, theirs)):
            gaps[i].append(b - a)
            own[i].append(a)
    print("| stretch | " + " | ".join(labels) + " |")
    print("|---|" + "---:|" * len(labels))
    print("| the comparator's gain less the row's | " + " | ".join(map(in_thousands, gaps)) + " |")
    print(
        "| the row's own gain, mean | "
        + " | ".join(f"{statistics.mean(g) / 1e3:.1f}k" for g in own)
        + " |"
    )


if __name__ == "__main__":
    main()
