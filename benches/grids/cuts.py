#!/usr/bin/env python3
"""The cuts at 60k read by the rules written before their runs (docs/dref-lunar-lander.md, "Do
the late answers matter? The cuts at 60k"; benches/grids/lunar-layer-norm-branches.jobs): per
seed, a row's run against its cut (the same run to a checkpoint at or before the cut, branched
there with `feedback_until`), by the late reward (the summed return of the episodes ending at or
after the cut) and the share of those episodes that fail; each seed's verdict, the means over
seeds, and the exact one-sided sign-flip test over seeds that the cut fails more.

    python3 benches/grids/cuts.py --reading ef-100 \\
        docs/results/dref-ablation/short-opening-layer-norm/lunar-lander/ef-100 \\
        docs/results/dref-ablation/short-opening-layer-norm/lunar-lander/ef-100-until-60k

`--reading ef-100`: the late edge is built by the cut if the cut keeps at least 0.9 of the late
reward and fails at most 0.05 of its late episodes; it is carried by the late answers if it keeps
less than 0.75 or fails at least 0.10; else no reading. `--reading dref`: the late trickle
carries something if the cut keeps less than 0.9 of the late reward or fails 0.05 or more above
the row; it is worth nothing measurable if it keeps at least 0.95 and fails within 0.03 of the
row; else no reading. Only seeds finished in both folders are read (`--seeds 9,5,7` reads only
those), and a cut whose summary does not say it branched at or before the cut step is refused.
Last, the whole runs paired: the cut's cumulative reward less the row's per seed, and the exact
one-sided sign-flip test that the cut ends above the row (the reading of DREF normed until 60k as
a row, lunar-layer-norm-until-60k.jobs).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from gap_stretches import finished_seeds
from late_asks import paired_p_above
from late_outcomes import Late, late_outcomes
from rows import mean_se, seed_list


def verdict(reading: str, row: Late, cut: Late) -> str:
    kept = cut.reward / row.reward
    if reading == "ef-100":
        if kept >= 0.9 and cut.failed <= 0.05:
            return "built by the cut"
        if kept < 0.75 or cut.failed >= 0.10:
            return "carried by the late answers"
        return "no reading"
    rise = cut.failed - row.failed
    if kept < 0.9 or rise >= 0.05:
        return "the trickle carries something"
    if kept >= 0.95 and abs(rise) <= 0.03:
        return "worth nothing measurable"
    return "no reading"


def branched_at(run: Path, cut_step: int) -> int:
    summary = json.loads((run / "summary.json").read_text())
    branch = summary.get("branched_from")
    until = summary.get("config", {}).get("feedback_until")
    if until != cut_step:
        raise SystemExit(f"{run}: feedback_until is {until}, not {cut_step}")
    if branch is not None and branch["step"] > cut_step:
        raise SystemExit(f"{run}: branched at {branch['step']}, after the cut at {cut_step}")
    return branch["step"] if branch else 0


def cumulative(run: Path) -> float:
    return json.loads((run / "summary.json").read_text())["cumulative_return"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reading", choices=["ef-100", "dref"], required=True)
    parser.add_argument("row", type=Path, help="the row's folder of seed<N>/ runs")
    parser.add_argument("cut", type=Path, help="its cut's folder of seed<N>/ runs")
    parser.add_argument("--at", type=int, default=60_000, help="the cut's feedback_until")
    parser.add_argument(
        "--seeds", type=seed_list, help="read only these seeds, e.g. 9,5,7 (default: every one)"
    )
    args = parser.parse_args()
    rows, cuts = finished_seeds(args.row), finished_seeds(args.cut)
    seeds = sorted(set(rows) & set(cuts))
    if args.seeds:
        seeds = [seed for seed in seeds if seed in args.seeds]
    if not seeds:
        raise SystemExit(f"no seed has finished in both {args.row} and {args.cut}")
    print(f"episodes ending at or after step {args.at}; seeds {seeds}; reading: {args.reading}")
    print(
        "| seed | branched at | row's late reward | cut's | kept | row fails | cut fails "
        "| rise | verdict |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    kept, fails, rises = [], [], []
    for seed in seeds:
        at = branched_at(cuts[seed], args.at)
        row, cut = late_outcomes(rows[seed], args.at), late_outcomes(cuts[seed], args.at)
        kept.append(cut.reward / row.reward)
        fails.append(cut.failed)
        rises.append(cut.failed - row.failed)
        print(
            f"| {seed} | {at:,} | {row.reward / 1e3:.1f}k | {cut.reward / 1e3:.1f}k "
            f"| {kept[-1]:.2f} | {row.failed:.2f} | {cut.failed:.2f} | {rises[-1]:+.2f} "
            f"| {verdict(args.reading, row, cut)} |"
        )
    if len(seeds) > 1:
        (k, ks), (f, fs), (r, rs) = mean_se(kept), mean_se(fails), mean_se(rises)
        print(
            f"over {len(seeds)} seeds: kept {k:.2f} +- {ks:.2f}, the cut fails {f:.2f} +- {fs:.2f}, "
            f"{r:+.2f} +- {rs:.2f} on the row; the cut fails more on "
            f"{sum(x > 0 for x in rises)} of {len(seeds)} seeds, exact one-sided sign-flip "
            f"p = {paired_p_above(rises):.4f}"
        )
        gains = [cumulative(cuts[seed]) - cumulative(rows[seed]) for seed in seeds]
        g, gs = mean_se(gains)
        print(
            f"whole runs: the cut's cumulative reward less the row's {g / 1e3:+.1f}k +- "
            f"{gs / 1e3:.1f}k, above on {sum(x > 0 for x in gains)} of {len(seeds)} seeds, exact "
            f"one-sided sign-flip p = {paired_p_above(gains):.4f}"
        )


if __name__ == "__main__":
    main()
