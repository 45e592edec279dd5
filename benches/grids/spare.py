#!/usr/bin/env python3
"""How far a run's repayment reserve (`spare` in core/src/guidance/ask_budget.rs) grew, from its
committed metrics.csv alone.

After the opening (`feedback_opening` steps, the bucket starting empty) a debt is repaid from
`opening_repay_share` of each step's earnings; the rest, `spare`, funds queries for the
best-ranked state while it repays, and is not capped at the burst. So at step t of the
repayment spare = (1 - share) * rate * (t - opening) - (queries asked since the opening), and
the debt is repaid at opening + debt / (share * rate). metrics.csv has the query count at each
episode's end, so spare is exact there once the opening's own count is known; the episode that
straddles the opening's end leaves that count between two values, and both bounds are given.

    python3 benches/grids/spare.py docs/results/fig3/placing/dref/seed*

Prints, per run: the opening's queries (the two bounds), the step the debt is repaid by, and
the largest spare at an episode's end during the repayment (lower and upper bound). A run
whose lower bound passes the burst (20) has held more than a capped reserve would hold.
"""
import csv
import json
import sys


def spare_range(run: str) -> str:
    config = json.load(open(f"{run}/config.json"))
    rule = config["query_rule"]
    ceiling = rule.get("ceiling") or {}
    rate = ceiling.get("rate", 0.1)
    opening = ceiling.get("opening", 2000)
    share = ceiling.get("repay_share", 0.9)
    rows = list(csv.DictReader(open(f"{run}/metrics.csv")))
    points = [(int(r["step"]), int(r["feedback_count"])) for r in rows]
    before = [c for s, c in points if s <= opening]
    after = [(s, c) for s, c in points if s > opening]
    if not after:
        return "no episode after the opening"
    bounds = sorted({before[-1] if before else 0, after[0][1]})
    out = []
    for asked in bounds:
        debt = asked - rate * opening
        if debt <= 0:
            out.append((asked, opening, 0.0))
            continue
        repaid = opening + debt / (share * rate)
        largest = max(
            ((1 - share) * rate * (s - opening) - (c - asked) for s, c in after[1:] if s <= repaid),
            default=0.0,
        )
        out.append((asked, repaid, largest))
    (lo_asked, lo_repaid, lo), (hi_asked, hi_repaid, hi) = out[0], out[-1]
    return (
        f"opening asked {lo_asked}-{hi_asked}, repaid by {lo_repaid / 1000:.1f}k-{hi_repaid / 1000:.1f}k, "
        f"largest spare {max(lo, 0):.1f} to {max(hi, 0):.1f}"
    )


if __name__ == "__main__":
    for run in sys.argv[1:]:
        print(f"{run}: {spare_range(run)}")
