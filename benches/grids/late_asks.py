#!/usr/bin/env python3
"""Where a row's late questions fall, by how the episodes end: for the episodes that end at or
after a step (60,000 by default, as late_outcomes.py cuts), each seed's questions per step in
the episodes that fail (crash or leave the screen), land and run to the time limit, the share of
its late questions spent in failing episodes against the share of late steps they take, and the
share of the answers there that were -1; mean +- s.e. over seeds, and an exact one-sided paired
test (every sign flip of the per-seed differences) that failing episodes are asked more densely
than landing ones (docs/dref-lunar-lander.md, "Where the late questions fall").

    python3 benches/grids/late_asks.py \
        docs/results/dref-ablation/short-opening-layer-norm/lunar-lander/dref [--from 60000]

A folder holds `seed<N>/` runs with metrics.csv (an episode's end step, length and outcome) and
answers.csv (its questions and their -1, 0 and +1 answers); finished runs only, and a run
without answers.csv (binaries before the twenty-seventh session) is named and left out.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import dataclass
from itertools import product
from pathlib import Path

from gap_stretches import finished_seeds
from rows import mean_se

OUTCOMES = ("failure", "success", "time_limit")


@dataclass
class ByOutcome:
    episodes: int = 0
    steps: int = 0
    asked: int = 0
    bad: int = 0
    good: int = 0

    def rate(self) -> float | None:
        return self.asked / self.steps if self.steps else None

    def bad_share(self) -> float | None:
        return self.bad / self.asked if self.asked else None

    def good_share(self) -> float | None:
        return self.good / self.asked if self.asked else None


def late_asks(run: Path, start: int) -> dict[str, ByOutcome]:
    with open(run / "answers.csv") as f:
        answers = {int(r["episode"]): r for r in csv.DictReader(f)}
    by = {o: ByOutcome() for o in OUTCOMES}
    with open(run / "metrics.csv") as f:
        for r in csv.DictReader(f):
            if int(r["step"]) < start:
                continue
            g = by[r["outcome"]]
            a = answers.get(int(r["episode"]))
            g.episodes += 1
            g.steps += int(r["length"])
            g.asked += int(a["asked"]) if a else 0
            g.bad += int(a["bad"]) if a else 0
            g.good += int(a["good"]) if a else 0
    return by


def paired_p_above(differences: list[float]) -> float:
    """P(sum >= observed) over every flip of the differences' signs (exact, ties counted)."""
    observed = sum(differences)
    flips = list(product((1, -1), repeat=len(differences)))
    hits = sum(sum(s * d for s, d in zip(signs, differences)) >= observed - 1e-12 for signs in flips)
    return hits / len(flips)


def fmt(v: float | None, digits: int = 4) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def late_row(doc: str) -> tuple[argparse.Namespace, dict[int, Path]]:
    """A script's one row and `--from` step from the command line, and the row's finished runs."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("row", type=Path, help="the row's folder of seed<N>/ runs")
    parser.add_argument("--from", dest="start", type=int, default=60_000)
    args = parser.parse_args()
    runs = finished_seeds(args.row)
    if not runs:
        raise SystemExit(f"no seed has finished in {args.row}")
    return args, runs


def main() -> None:
    args, runs = late_row(__doc__)
    print(f"{args.row}: episodes ending at or after step {args.start}")
    print(
        "| seed | asks a step: fail | land | time limit | fail / land "
        "| late asks in failing episodes | late steps in them | -1 share: fail | land |"
    )
    print("|---|" + "---:|" * 8)
    ratios, differences, ask_shares, step_shares, rates = [], [], [], [], []
    for seed in sorted(runs):
        if not (runs[seed] / "answers.csv").exists():
            print(f"| {seed} | no answers.csv: left out |" + " |" * 7)
            continue
        by = late_asks(runs[seed], args.start)
        fail, land, limit = (by[o] for o in OUTCOMES)
        asked = sum(g.asked for g in by.values())
        steps = sum(g.steps for g in by.values())
        ratio = None
        if fail.rate() is not None and land.rate():
            ratio = fail.rate() / land.rate()
            ratios.append(ratio)
            differences.append(fail.rate() - land.rate())
        rates.append(asked / steps if steps else 0.0)
        ask_share = fail.asked / asked if asked else None
        step_share = fail.steps / steps if steps else None
        if ask_share is not None and step_share is not None:
            ask_shares.append(ask_share)
            step_shares.append(step_share)
        print(
            f"| {seed} | {fmt(fail.rate())} | {fmt(land.rate())} | {fmt(limit.rate())} "
            f"| {fmt(ratio, 2)} | {fmt(ask_share, 3)} | {fmt(step_share, 3)} "
            f"| {fmt(fail.bad_share(), 2)} | {fmt(land.bad_share(), 2)} |"
        )
    if rates:
        m, se = mean_se(rates)
        print(f"late asks a step, every late episode, over {len(rates)} seeds: {m:.4f} +- {se:.4f}")
    if len(ratios) >= 2:
        m, se = mean_se(ratios)
        print(f"fail / land over {len(ratios)} seeds: {m:.2f} +- {se:.2f}")
        m_a, se_a = mean_se(ask_shares)
        m_s, se_s = mean_se(step_shares)
        print(
            f"late asks in failing episodes {m_a:.3f} +- {se_a:.3f} of the asks, "
            f"on {m_s:.3f} +- {se_s:.3f} of the late steps"
        )
        print(
            f"failing episodes asked more densely than landing ones: {sum(d > 0 for d in differences)} "
            f"of {len(differences)} seeds, exact one-sided sign-flip p = {paired_p_above(differences):.4f}"
        )
    else:
        print("too few seeds asked late in both landing and failing episodes to compare")


if __name__ == "__main__":
    main()
