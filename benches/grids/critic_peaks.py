#!/usr/bin/env python3
"""Whether a Lunar Lander run's end is the learner's: each run's peak env-critic loss (the
highest mean of `critic_loss` over a 10k-step stretch of learner.csv) beside its cumulative
reward, and Spearman's rank correlation between the two over every run given.

    python3 benches/grids/critic_peaks.py docs/results/fig3-as-run/lunar-lander/ef-2.79 \
        docs/results/dref-ablation/*/lunar-lander/*

Every finished run (`seed<N>/summary.json`) that has a learner.csv is counted, whatever its row:
the question is about the learner, which every row shares. Runs whose critics fit with the Huber
loss (`critic_loss = "huber"` in config.json) log another quantity and are left out, by name. The p value is `early_answers.py`'s
permutation test of rho against no association (one-sided, rho below zero), 200,000 shuffles
drawn from a fixed seed, so it reads the same on every machine.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

from early_answers import permutation_p, spearman

STRETCH = 10_000
SHUFFLES = 200_000


def peak_critic_loss(learner_csv: Path) -> float:
    """The highest mean critic loss over a `STRETCH`-step stretch of a run."""
    stretches: dict[int, list[float]] = {}
    with open(learner_csv) as f:
        for row in csv.DictReader(f):
            stretches.setdefault(int(row["step"]) // STRETCH, []).append(float(row["critic_loss"]))
    return max(sum(v) / len(v) for v in stretches.values())


def main(folders: list[str]) -> None:
    runs = []
    for folder in folders:
        for seed_dir in sorted(Path(folder).glob("seed*")):
            summary, learner = seed_dir / "summary.json", seed_dir / "learner.csv"
            if summary.exists() and learner.exists():
                config = json.loads((seed_dir / "config.json").read_text())
                if config.get("sac", {}).get("critic_loss", "mse") != "mse":
                    print(f"left out (critic loss {config['sac']['critic_loss']}): {seed_dir}")
                    continue
                cumulative = json.loads(summary.read_text())["cumulative_return"]
                runs.append((peak_critic_loss(learner), cumulative, str(seed_dir)))
    if len(runs) < 3:
        sys.exit("fewer than 3 finished runs with a learner.csv")
    for peak, cumulative, name in sorted(runs):
        print(f"{peak:9.1f} {cumulative / 1000:8.1f}k  {name}")
    peaks, sums = [r[0] for r in runs], [r[1] for r in runs]
    rho, p = spearman(peaks, sums), permutation_p(peaks, sums, SHUFFLES)
    print(
        f"{len(runs)} runs: Spearman rho (peak critic loss, cumulative reward) = {rho:.3f}, "
        f"one-sided permutation p = {p:.2g}"
    )


if __name__ == "__main__":
    main(sys.argv[1:])
