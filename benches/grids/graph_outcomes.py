#!/usr/bin/env python3
"""What Lunar Lander's scene graph tells of how a descent ends: from `dualrep sim --steps` (every
step of a noisy heuristic's episodes, with the product's abstract state), the steps shortly
before each episode's end, labelled by whether it ended failed (crash or off the screen) or
landed; episodes that reach the time limit are left out. For each way of cutting the steps into
cells, the share of the outcome's entropy the cell carries (plug-in, pooled steps) and the
held-out AUC of the cell's failure share as a score (fitted on the episodes of even seeds,
scored on the odd ones and the other way round, averaged) (docs/dref-lunar-lander.md, "What the
scene graph can see of a landing").

    target/release/dualrep sim --task lunar-lander --episodes 2000 --noise 0.6 --steps steps.csv
    python3 benches/grids/graph_outcomes.py steps.csv [--before 55] [--skip 5]

The cuts: the graph's abstract state; the graph with one more predicate, on falling speed
(`obs_3` above its median over the window's steps); and the falling speed alone, in as many
equal-count bins as the graph fills, so that a cut of the same size on the low-level state is
beside it.
"""

from __future__ import annotations

import argparse
import csv
import math
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path

from rows import midranks


@dataclass
class WindowStep:
    seed: int
    state: str
    fall_speed: float
    failed: bool


def window_steps(path: Path, before: int, skip: int) -> tuple[list[WindowStep], Counter[str]]:
    """The steps t with length - before <= t < length - skip of every episode that landed or
    failed, and how many episodes ended each way."""
    episodes: dict[int, list[dict[str, str]]] = defaultdict(list)
    with path.open() as f:
        for row in csv.DictReader(f):
            episodes[int(row["seed"])].append(row)
    endings: Counter[str] = Counter()
    steps: list[WindowStep] = []
    for seed, rows in episodes.items():
        outcome = rows[-1]["outcome"]
        endings[outcome] += 1
        if outcome not in ("success", "failure"):
            continue
        n = len(rows)
        for row in rows[max(0, n - before) : max(0, n - skip)]:
            steps.append(
                WindowStep(seed, row["abstract_state"], float(row["obs_3"]), outcome == "failure")
            )
    return steps, endings


def entropy(p: float) -> float:
    return 0.0 if p in (0.0, 1.0) else -(p * math.log2(p) + (1 - p) * math.log2(1 - p))


def information_share(cells: list[str], failed: list[bool]) -> float:
    """I(outcome; cell) / H(outcome), plug-in over the pooled steps."""
    total = len(cells)
    base = entropy(sum(failed) / total)
    by_cell: dict[str, list[bool]] = defaultdict(list)
    for c, y in zip(cells, failed):
        by_cell[c].append(y)
    conditional = sum(len(ys) / total * entropy(sum(ys) / len(ys)) for ys in by_cell.values())
    return (base - conditional) / base if base > 0 else 0.0


def held_out_auc(cells: list[str], failed: list[bool], seeds: list[int]) -> float:
    """The AUC of each cell's failure share (fitted on one half of the episodes, with one prior
    step at the fitted half's base rate) as a score for the other half's steps; both ways,
    averaged."""
    aucs = []
    for fit_parity in (0, 1):
        fit = [(c, y) for c, y, s in zip(cells, failed, seeds) if s % 2 == fit_parity]
        base = sum(y for _, y in fit) / len(fit)
        counts: dict[str, list[float]] = defaultdict(lambda: [base, 1.0])
        for c, y in fit:
            counts[c][0] += y
            counts[c][1] += 1
        scored = [
            (counts[c][0] / counts[c][1] if c in counts else base, y)
            for c, y, s in zip(cells, failed, seeds)
            if s % 2 != fit_parity
        ]
        ranks = midranks([score for score, _ in scored])
        n_failed = sum(y for _, y in scored)
        n_landed = len(scored) - n_failed
        # Mann-Whitney's U of the failed steps' scores over the landed ones', from midranks
        # (rows.py's pairwise u_statistic is quadratic, too slow for this many steps).
        u = sum(r for r, (_, y) in zip(ranks, scored) if y) - n_failed * (n_failed + 1) / 2
        aucs.append(u / (n_failed * n_landed))
    return sum(aucs) / len(aucs)


def equal_count_bins(values: list[float], bins: int) -> list[str]:
    order = sorted(values)
    edges = [order[len(order) * i // bins] for i in range(1, bins)]
    return [str(sum(v >= e for e in edges)) for v in values]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("steps", type=Path, help="a `dualrep sim --steps` file (Lunar Lander)")
    parser.add_argument("--before", type=int, default=55, help="window start, steps before the end")
    parser.add_argument("--skip", type=int, default=5, help="steps left out at the very end")
    args = parser.parse_args()
    if not 0 <= args.skip < args.before:
        parser.error(f"--skip {args.skip} must be at least 0 and below --before {args.before}")

    steps, endings = window_steps(args.steps, args.before, args.skip)
    failed = [s.failed for s in steps]
    seeds = [s.seed for s in steps]
    ended = endings["success"] + endings["failure"]
    print(
        f"episodes: {sum(endings.values())} ({endings['success']} landed, "
        f"{endings['failure']} failed, {endings['time_limit']} time limit); "
        f"of those that landed or failed, {endings['failure'] / ended:.3f} failed"
    )
    print(
        f"window: steps {args.before} to {args.skip} before the end, {len(steps)} steps, "
        f"{sum(failed) / len(steps):.3f} of them in failed episodes"
    )
    graph = [s.state for s in steps]
    median = sorted(s.fall_speed for s in steps)[len(steps) // 2]
    graph_speed = [f"{s.state}{int(s.fall_speed > median)}" for s in steps]
    filled = len(set(graph))
    speed_bins = equal_count_bins([s.fall_speed for s in steps], filled)
    print("| cut | cells | outcome entropy carried | held-out AUC |")
    print("|---|---:|---:|---:|")
    for name, cells in (
        ("the scene graph", graph),
        (f"the graph + falling speed above its median ({median:.3f})", graph_speed),
        ("falling speed alone, equal-count bins", speed_bins),
    ):
        print(
            f"| {name} | {len(set(cells))} | {information_share(cells, failed):.3f} "
            f"| {held_out_auc(cells, failed, seeds):.3f} |"
        )


if __name__ == "__main__":
    main()
