#!/usr/bin/env python3
"""Whether the teacher's late answers favour hovering: for the episodes that end at or after a
step (60,000 by default), each seed's answers grouped by how their episode ended (land, fail, run
to the time limit), the share of them that were +1, and the exact one-sided sign-flip test over
seeds that the share is higher in the episodes that run to the time limit than in those that land
(docs/results/dref-ablation/short-opening-layer-norm/README.md, "Seed 6's cuts").

    python3 benches/grids/answers_by_outcome.py \
        docs/results/dref-ablation/short-opening-layer-norm/lunar-lander/ef-100

Each run's answers.csv holds one row per episode (its answers asked, +1, -1 and none); the
episode's outcome comes from metrics.csv. A seed with no answered episode of either kind after
the step is left out of the test, by name.
"""

from __future__ import annotations

import csv
from pathlib import Path

from late_asks import late_row, paired_p_above
from rows import mean_se

OUTCOMES = [("success", "land"), ("failure", "fail"), ("time_limit", "time limit")]


def answers_by_outcome(run: Path, start: int) -> dict[str, tuple[int, int]]:
    """Per outcome, (answers asked, of them +1) over the episodes ending at or after `start`."""
    with open(run / "metrics.csv") as f:
        outcome = {r["episode"]: r["outcome"] for r in csv.DictReader(f) if int(r["step"]) >= start}
    if not (run / "answers.csv").exists():
        raise SystemExit(f"{run}: no answers.csv (runs from before answers were logged have none)")
    totals = {name: (0, 0) for name, _ in OUTCOMES}
    with open(run / "answers.csv") as f:
        for r in csv.DictReader(f):
            if r["episode"] in outcome:
                asked, good = totals[outcome[r["episode"]]]
                totals[outcome[r["episode"]]] = (asked + int(r["asked"]), good + int(r["good"]))
    return totals


def share(asked_good: tuple[int, int]) -> float | None:
    asked, good = asked_good
    return good / asked if asked else None


def main() -> None:
    args, runs = late_row(__doc__)
    print(f"{args.row}: answers in episodes ending at or after step {args.start}")
    print("| seed | " + " | ".join(f"{label}: asked, +1" for _, label in OUTCOMES) + " |")
    print("|---:|" + "---:|" * len(OUTCOMES))
    differences, left_out = [], []
    for seed, run in sorted(runs.items()):
        totals = answers_by_outcome(run, args.start)
        cells = [
            f"{totals[name][0]:,}, " + ("-" if share(totals[name]) is None else f"{share(totals[name]):.2f}")
            for name, _ in OUTCOMES
        ]
        print(f"| {seed} | " + " | ".join(cells) + " |")
        hover, land = share(totals["time_limit"]), share(totals["success"])
        if hover is None or land is None:
            left_out.append(seed)
        else:
            differences.append(hover - land)
    if left_out:
        print(f"left out of the test (no answered landing or time-limit episode): seeds {left_out}")
    if len(differences) > 1:
        mean, se = mean_se(differences)
        print(
            f"+1 share in time-limit episodes less that in landing ones: {mean:+.2f} +- {se:.2f}, "
            f"higher on {sum(d > 0 for d in differences)} of {len(differences)} seeds, "
            f"exact one-sided sign-flip p = {paired_p_above(differences):.4f}"
        )


if __name__ == "__main__":
    main()
