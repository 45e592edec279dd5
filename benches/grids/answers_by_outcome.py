#!/usr/bin/env python3
"""Whether the teacher's late answers favour hovering: for the episodes that end at or after a
step (60,000 by default), each seed's answers grouped by how their episode ended (land, fail, run
to the time limit; late_asks.py's grouping), the share of them that were +1, and the exact
one-sided sign-flip test over seeds that the share is higher in the episodes that run to the time
limit than in those that land (docs/results/dref-ablation/short-opening-layer-norm/README.md,
"Seed 6's cuts").

    python3 benches/grids/answers_by_outcome.py \
        docs/results/dref-ablation/short-opening-layer-norm/lunar-lander/ef-100 [--from 60000]

Each run's answers.csv holds one row per episode (its answers asked, +1, -1 and none); the
episode's outcome comes from metrics.csv. A run without answers.csv, or with no answered landing
or time-limit episode after the step, is named and left out of the test.
"""

from __future__ import annotations

from late_asks import OUTCOMES, fmt, late_asks, late_row, paired_p_above
from rows import mean_se

LABELS = {"failure": "fail", "success": "land", "time_limit": "time limit"}


def main() -> None:
    args, runs = late_row(__doc__)
    print(f"{args.row}: answers in episodes ending at or after step {args.start}")
    print("| seed | " + " | ".join(f"{LABELS[o]}: asked, +1" for o in OUTCOMES) + " |")
    print("|---:|" + "---:|" * len(OUTCOMES))
    differences, left_out = [], []
    for seed, run in sorted(runs.items()):
        if not (run / "answers.csv").exists():
            print(f"| {seed} | no answers.csv: left out |" + " |" * (len(OUTCOMES) - 1))
            continue
        by = late_asks(run, args.start)
        cells = [f"{by[o].asked:,}, {fmt(by[o].good_share(), 2)}" for o in OUTCOMES]
        print(f"| {seed} | " + " | ".join(cells) + " |")
        hover, land = by["time_limit"].good_share(), by["success"].good_share()
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
