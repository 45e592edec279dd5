#!/usr/bin/env python3
"""Per-seed rows of one method's runs, their mean +- s.e., and (with a second folder) the exact
one-sided Mann-Whitney test that the first row lies above the second.

    python3 benches/grids/rows.py docs/results/dref-ablation/ablation-window/placing/dref-authors \
        [docs/results/fig3/placing/dref-authors] [--seeds 9,5,7]

A folder holds `seed<N>/` runs (summary.json, metrics.csv). Each run's line: cumulative reward,
feedback % (and, where the run has answers.csv, the share of its answers that were +1), longest
flood after 2k steps, successes in its last 10 episodes (on Lunar Lander with their mean return),
wall seconds and kernels; a run learns as the report says (8 or more of its
last 10 succeed; on Lunar Lander their mean return is 200 or more). The test counts ties as one
half and enumerates every split of the pooled ranks, so its p is exact for the seeds given (no
normal approximation). `--seeds` reads only the seeds it names, in both folders.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from functools import lru_cache
from pathlib import Path


def runs(folder: Path) -> list[dict]:
    rows = []
    for seed_dir in sorted(folder.glob("seed*"), key=lambda p: int(p.name[4:])):
        summary_path = seed_dir / "summary.json"
        if not summary_path.exists():
            continue
        summary = json.loads(summary_path.read_text())
        with open(seed_dir / "metrics.csv") as f:
            episodes = list(csv.DictReader(f))
        last = episodes[-10:]
        summary["last10_episodes"] = last
        summary["last10"] = sum(e["outcome"] == "success" for e in last)
        summary["last10_return"] = mean_return(last)
        summary["good_share"] = good_share(seed_dir)
        rows.append(summary)
    return rows


def good_share(seed_dir: Path) -> float | None:
    """The share of a run's answers that were +1 (answers.csv, where the run has one; `None`
    without one or without answers)."""
    path = seed_dir / "answers.csv"
    if not path.exists():
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    asked = sum(int(r["asked"]) for r in rows)
    return sum(int(r["good"]) for r in rows) / asked if asked else None


def mean_return(window: list[dict[str, str]]) -> float:
    """The mean return of some episodes (metrics.csv rows); 0 for none."""
    return sum(float(e["return"]) for e in window) / max(len(window), 1)


def episodes_learnt(window: list[dict[str, str]], lunar_lander: bool) -> bool:
    """The report's rule over 10 episodes (metrics.csv rows): 8 or more succeed; on Lunar
    Lander, whose landings do not all score alike, their mean return is 200 or more."""
    if lunar_lander:
        return mean_return(window) >= 200.0
    return sum(e["outcome"] == "success" for e in window) >= 8


def learns(run: dict) -> bool:
    """Whether a run's last 10 episodes pass the report's rule."""
    return episodes_learnt(run["last10_episodes"], run.get("task") == "lunar-lander")


def mean_se(values: list[float]) -> tuple[float, float]:
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, 0.0
    var = sum((v - mean) ** 2 for v in values) / (n - 1)
    return mean, math.sqrt(var / n)


def midranks(values: list[float]) -> list[float]:
    """Each value's rank from 1 in the input's order, tied values sharing their mean rank."""
    order = sorted(range(len(values)), key=lambda i: values[i])
    ranks = [0.0] * len(values)
    i = 0
    while i < len(order):
        j = i
        while j < len(order) and values[order[j]] == values[order[i]]:
            j += 1
        for k in order[i:j]:
            ranks[k] = (i + j + 1) / 2
        i = j
    return ranks


def u_statistic(xs: list[float], ys: list[float]) -> float:
    return sum(1.0 if x > y else 0.5 if x == y else 0.0 for x in xs for y in ys)


def exact_p_above(xs: list[float], ys: list[float]) -> tuple[float, float]:
    """U of xs over ys and P(U >= observed) over every assignment of the pooled values."""
    pooled = sorted(xs + ys)
    observed = u_statistic(xs, ys)
    n, m = len(xs), len(ys)
    # Midranks make U = R_x - n(n+1)/2 with ties counted as one half.
    doubled = tuple(int(round(2 * r)) for r in midranks(pooled))

    @lru_cache(maxsize=None)
    def count(k: int, picks: int) -> dict[int, int]:
        # Ways to choose `picks` of the first k ranks, by their doubled rank sum.
        if picks == 0:
            return {0: 1}
        if k < picks:
            return {}
        out = dict(count(k - 1, picks))
        for s, c in count(k - 1, picks - 1).items():
            out[s + doubled[k - 1]] = out.get(s + doubled[k - 1], 0) + c
        return out

    total = math.comb(n + m, n)
    threshold = 2 * (observed + n * (n + 1) / 2)
    hits = sum(c for s, c in count(n + m, n).items() if s >= threshold - 1e-9)
    return observed, hits / total


def answered_good(run: dict) -> str:
    share = run.get("good_share")
    return "" if share is None else f", {100 * share:.0f} % of answers +1"


def last10_return(run: dict) -> str:
    if run.get("task") != "lunar-lander":
        return ""
    return f" (mean return {run['last10_return']:.1f})"


def seed_list(text: str) -> set[int]:
    """`--seeds 9,5,7` as a set; argparse names the option and the text when it does not read."""
    try:
        return {int(seed) for seed in text.split(",")}
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds such as 9,5,7, got {text!r}") from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", type=Path, nargs="+", help="one or two folders of seed<N>/ runs")
    parser.add_argument(
        "--seeds", type=seed_list, help="read only these seeds, e.g. 9,5,7 (default: every one)"
    )
    args = parser.parse_args()
    if len(args.folders) > 2:
        parser.error(f"at most two folders, got {len(args.folders)}")
    wanted = args.seeds
    groups = []
    for folder in args.folders:
        rows = [r for r in runs(folder) if wanted is None or r["seed"] in wanted]
        print(folder)
        for r in rows:
            print(
                f"  seed {r['seed']}: {r['cumulative_return'] / 1000:.1f}k at "
                f"{100 * r['feedback_fraction']:.2f} %{answered_good(r)}, flood after 2k "
                f"{r.get('longest_flood_after_2k', '-')}, last 10: {r['last10']}"
                f"{last10_return(r)}, "
                f"{r.get('wall_seconds', 0):.0f} s, {r.get('kernels', 'portable')}"
            )
        values = [r["cumulative_return"] for r in rows]
        if values:
            mean, se = mean_se(values)
            fb_mean, _ = mean_se([100 * r["feedback_fraction"] for r in rows])
            learn = sum(learns(r) for r in rows)
            print(
                f"  {len(values)} seeds: {mean / 1000:.1f}k +- {se / 1000:.1f}k at "
                f"{fb_mean:.2f} %, {learn} learn"
            )
        groups.append(values)
    if len(groups) == 2 and groups[0] and groups[1]:
        u, p = exact_p_above(groups[0], groups[1])
        print(
            f"first above second: U = {u:g} of {len(groups[0]) * len(groups[1])}, "
            f"one-sided exact p = {p:.4f}"
        )


if __name__ == "__main__":
    main()
