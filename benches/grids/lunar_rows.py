#!/usr/bin/env python3
"""Every committed 150k-step Lunar Lander row on one table, each beside EF-100 on the same
learner and teacher over the same seeds: what issue 34's aim (0.9 of EF-100's mean, at most
10 % of the steps answered) is judged against, and what each share of the answers has bought.

    python3 benches/grids/lunar_rows.py [docs/results]

A row is a folder of `seed<N>/` runs with summary.json at 150,000 steps. Its comparator is
EF-100 of the same family: `huber-critic/` rows against EF-100 on the Huber learner, the as-run
rows and the teacher at 0.99 against the as-run EF-100 (the oracle from alpha 0.99), every other
row against EF-100 at the repository head's constants (`fig3-lunar-lander-150k/`). The ratio is
the row's mean over the comparator's mean on the row's own seeds; the per-seed ratios follow.
Rows answered on every step (EF-100 itself) and SAC alone are listed for scale. A seed on which
EF-100 ended below zero (the head's seed 4) has no per-seed ratio.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from rows import learns, mean_se, runs

HEAD_EF100 = "fig3-lunar-lander-150k/lunar-lander/ef-100"
AS_RUN_EF100 = "fig3-as-run/lunar-lander/ef-100"
HUBER_EF100 = "huber-critic/lunar-lander/ef-100"


def comparator(row: str) -> str:
    if row.startswith("huber-critic/"):
        return HUBER_EF100
    if row.startswith("fig3-as-run/") or row.startswith("dref-ablation/teacher-099/"):
        return AS_RUN_EF100
    return HEAD_EF100


def seed_ratio(value: float, ef100: float) -> str:
    """One seed's ratio; none where EF-100 itself ended below zero (the sign would flip)."""
    return f"{value / ef100:.2f}" if ef100 > 0 else "(EF-100 < 0)"


def lunar_rows(results: Path) -> list[str]:
    """Folders under `results` whose runs are all 150k-step evaluative Lunar Lander runs."""
    by_folder: dict[str, list[dict]] = {}
    for path in results.glob("**/seed*/summary.json"):
        rel = path.parent.parent.relative_to(results).as_posix()
        if "lunar-lander" in rel and "probes" not in rel:
            by_folder.setdefault(rel, []).append(json.loads(path.read_text()))
    return sorted(
        rel for rel, summaries in by_folder.items() if all(map(evaluative_150k, summaries))
    )


def evaluative_150k(summary: dict) -> bool:
    """A 150k-step Lunar Lander run with a feedback share (DREF, EF, SAC; not DRPL's)."""
    return (
        summary.get("steps") == 150_000
        and summary.get("task") == "lunar-lander"
        and "feedback_fraction" in summary
        and not summary["method"].startswith("drpl")
    )


def main() -> None:
    results = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/results")
    ef100 = {
        name: {r["seed"]: r["cumulative_return"] for r in runs(results / name)}
        for name in (HEAD_EF100, AS_RUN_EF100, HUBER_EF100)
    }
    print(
        "| row | seeds | cumulative reward | feedback | learn | / EF-100, same seeds | "
        "per seed |"
    )
    print("|---|---|---:|---:|---:|---:|---|")
    for rel in lunar_rows(results):
        got = runs(results / rel)
        seeds = [r["seed"] for r in got]
        values = [r["cumulative_return"] for r in got]
        mean, se = mean_se(values)
        feedback, _ = mean_se([100 * r["feedback_fraction"] for r in got])
        base = ef100[comparator(rel)]
        shared = [s for s in seeds if s in base]
        if shared and len(shared) == len(seeds):
            base_mean = sum(base[s] for s in shared) / len(shared)
            ratio = f"{mean / base_mean:.2f}"
            per_seed = " ".join(seed_ratio(r["cumulative_return"], base[r["seed"]]) for r in got)
        else:
            ratio, per_seed = "-", "comparator lacks a seed"
        print(
            f"| `{rel}` | {','.join(map(str, seeds))} | {mean / 1000:.1f}k +- {se / 1000:.1f}k "
            f"| {feedback:.2f} % | {sum(learns(r) for r in got)} of {len(got)} | {ratio} "
            f"| {per_seed} |"
        )


if __name__ == "__main__":
    main()
