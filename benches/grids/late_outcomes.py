#!/usr/bin/env python3
"""How a row's episodes end once the learners have taken off: for the episodes that end at or
after a step (60,000 by default), each seed's count and its shares that land, fail (crash or
leave the screen) and run to the time limit, their mean return and summed reward; mean +- s.e.
over the seeds, and with a comparator, one-sided exact Mann-Whitney tests (rows.py's) on the
shares (docs/dref-lunar-lander.md, "What the late gap is made of").

    python3 benches/grids/late_outcomes.py \
        docs/results/fig3-lunar-lander-150k/lunar-lander/dref \
        docs/results/fig3-lunar-lander-150k/lunar-lander/ef-100 [--from 60000]

Each folder holds `seed<N>/` runs with metrics.csv (one row per finished episode: its end step,
return and outcome). Only finished runs (summary.json) are read, and with a comparator only the
seeds both rows have, so a grid still running adds nothing.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import dataclass
from pathlib import Path

from gap_stretches import finished_seeds
from rows import exact_p_above, mean_return, mean_se


@dataclass
class Late:
    episodes: int
    landed: float
    failed: float
    time_limit: float
    mean_return: float
    reward: float


def late_outcomes(run: Path, start: int) -> Late:
    with open(run / "metrics.csv") as f:
        late = [r for r in csv.DictReader(f) if int(r["step"]) >= start]
    if not late:
        raise SystemExit(f"{run}: no episode ends at or after step {start}")
    n = len(late)

    def share(outcome: str) -> float:
        return sum(r["outcome"] == outcome for r in late) / n

    return Late(
        episodes=n,
        landed=share("success"),
        failed=share("failure"),
        time_limit=share("time_limit"),
        mean_return=mean_return(late),
        reward=sum(float(r["return"]) for r in late),
    )


FIELDS = [
    ("episodes", "episodes", lambda v: f"{v:.0f}"),
    ("landed", "land", lambda v: f"{v:.2f}"),
    ("failed", "fail", lambda v: f"{v:.2f}"),
    ("time_limit", "time limit", lambda v: f"{v:.2f}"),
    ("mean_return", "mean return", lambda v: f"{v:.1f}"),
    ("reward", "reward", lambda v: f"{v / 1e3:.1f}k"),
]


def summary(runs: dict[int, Late]) -> str:
    cells = []
    for field, _, fmt in FIELDS:
        mean, se = mean_se([getattr(r, field) for r in runs.values()])
        cells.append(fmt(mean) if len(runs) < 2 else f"{fmt(mean)} +- {fmt(se)}")
    return " | ".join(cells)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("row", type=Path, help="the row's folder of seed<N>/ runs")
    parser.add_argument("comparator", type=Path, nargs="?", help="e.g. the ef-100 folder")
    parser.add_argument("--from", dest="start", type=int, default=60_000)
    args = parser.parse_args()
    folders = [args.row] + ([args.comparator] if args.comparator else [])
    finished = [finished_seeds(folder) for folder in folders]
    seeds = sorted(set.intersection(*(set(f) for f in finished)))
    if not seeds:
        raise SystemExit("no seed has finished in " + " and ".join(map(str, folders)))
    rows = [{s: late_outcomes(f[s], args.start) for s in seeds} for f in finished]
    names = [folder.name for folder in folders]
    if len(set(names)) < len(names):
        # Two rows of one method (`.../<row>/<task>/dref`): name each by its row's folder too.
        names = [f"{folder.parent.parent.name}/{folder.name}" for folder in folders]
    print(f"episodes ending at or after step {args.start}; seeds {seeds}")
    print("| row | " + " | ".join(label for _, label, _ in FIELDS) + " |")
    print("|---|" + "---:|" * len(FIELDS))
    for name, runs in zip(names, rows):
        for seed, late in runs.items():
            cells = [fmt(getattr(late, field)) for field, _, fmt in FIELDS]
            print(f"| {name} seed {seed} | " + " | ".join(cells) + " |")
        print(f"| **{name}, {len(runs)} seeds** | {summary(runs)} |")
    if len(rows) == 2:
        mine, theirs = rows
        tests = (
            ("failed", "fails more", True),
            ("landed", "lands less", False),
            ("time_limit", "runs to the limit more", True),
        )
        for field, label, above in tests:
            xs = [getattr(mine[s], field) for s in seeds]
            ys = [getattr(theirs[s], field) for s in seeds]
            u, p = exact_p_above(xs, ys) if above else exact_p_above(ys, xs)
            print(
                f"{names[0]} {label} than {names[1]}: "
                f"U = {u:g} of {len(xs) * len(ys)}, one-sided exact p = {p:.4f}"
            )


if __name__ == "__main__":
    main()
