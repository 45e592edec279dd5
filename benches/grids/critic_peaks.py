#!/usr/bin/env python3
"""Whether a Lunar Lander run's end is the learner's: each run's peak env-critic loss (the
highest mean of `critic_loss` over a 10k-step stretch of learner.csv) beside its cumulative
reward, and Spearman's rank correlation between the two over every run given.

    python3 benches/grids/critic_peaks.py docs/results/fig3-as-run/lunar-lander/ef-2.79 \
        docs/results/dref-ablation/*/lunar-lander/*

Every finished run (`seed<N>/summary.json`) that has a learner.csv is counted, whatever its row:
the question is about the learner, which every row shares. The p value is a permutation test of
rho against no association (one-sided, rho below zero), 200,000 shuffles drawn from a fixed seed,
so it reads the same on every machine.
"""

from __future__ import annotations

import csv
import json
import random
import sys
from pathlib import Path

from rows import midranks

STRETCH = 10_000
SHUFFLES = 200_000


def peak_critic_loss(learner_csv: Path) -> float:
    """The highest mean critic loss over a `STRETCH`-step stretch of a run."""
    stretches: dict[int, list[float]] = {}
    with open(learner_csv) as f:
        for row in csv.DictReader(f):
            stretches.setdefault(int(row["step"]) // STRETCH, []).append(float(row["critic_loss"]))
    return max(sum(v) / len(v) for v in stretches.values())


def pearson(a: list[float], b: list[float]) -> float:
    ma, mb = sum(a) / len(a), sum(b) / len(b)
    cov = sum((x - ma) * (y - mb) for x, y in zip(a, b))
    va = sum((x - ma) ** 2 for x in a)
    vb = sum((y - mb) ** 2 for y in b)
    return cov / (va * vb) ** 0.5


def main(folders: list[str]) -> None:
    runs = []
    for folder in folders:
        for seed_dir in sorted(Path(folder).glob("seed*")):
            summary, learner = seed_dir / "summary.json", seed_dir / "learner.csv"
            if summary.exists() and learner.exists():
                cumulative = json.loads(summary.read_text())["cumulative_return"]
                runs.append((peak_critic_loss(learner), cumulative, str(seed_dir)))
    if len(runs) < 3:
        sys.exit("fewer than 3 finished runs with a learner.csv")
    for peak, cumulative, name in sorted(runs):
        print(f"{peak:9.1f} {cumulative / 1000:8.1f}k  {name}")
    peaks, sums = midranks([r[0] for r in runs]), midranks([r[1] for r in runs])
    rho = pearson(peaks, sums)
    rng = random.Random(0)
    shuffled = list(sums)
    below = 0
    for _ in range(SHUFFLES):
        rng.shuffle(shuffled)
        below += pearson(peaks, shuffled) <= rho
    print(
        f"{len(runs)} runs: Spearman rho (peak critic loss, cumulative reward) = {rho:.3f}, "
        f"one-sided permutation p = {(below + 1) / (SHUFFLES + 1):.2g}"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
