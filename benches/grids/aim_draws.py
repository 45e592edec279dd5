#!/usr/bin/env python3
"""How often a row of N seeds drawn from a method's own runs reaches a share of a reference
row's mean: the noise of an aim such as "DREF >= 0.9 of EF-100's mean over five seeds".

    python3 benches/grids/aim_draws.py docs/results/fig3-lunar-lander-150k/lunar-lander/ef-100 \
        [docs/results/fig3-lunar-lander-150k/lunar-lander/ef-50 ...] [--share 0.9] [--seeds 5]

The first folder is the reference (its mean sets the bar, share x mean); every folder given,
the reference too, is drawn from: N seeds with replacement from its committed runs, every one of
the len(runs)^N ordered draws enumerated, so the fraction printed is exact for those runs taken
as the method's whole distribution.
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

from rows import mean_se, runs

# Enumerating is exact; past this many draws it takes minutes.
MAX_DRAWS = 10_000_000


def share_reaching(values: list[float], bar: float, seeds: int) -> float:
    """The fraction of ordered draws of `seeds` values from `values` whose mean is >= `bar`."""
    hits = total = 0
    for draw in itertools.product(values, repeat=seeds):
        total += 1
        hits += sum(draw) / seeds >= bar
    return hits / total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--share", type=float, default=0.9)
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args()
    reference = [r["cumulative_return"] for r in runs(args.folders[0])]
    if not reference:
        raise SystemExit(f"{args.folders[0]}: no finished runs (seed*/summary.json)")
    ref_mean, ref_se = mean_se(reference)
    bar = args.share * ref_mean
    print(
        f"bar: {args.share} x {ref_mean / 1000:.1f}k (s.e. {ref_se / 1000:.1f}k, "
        f"{len(reference)} runs) = {bar / 1000:.1f}k"
    )
    for folder in args.folders:
        values = [r["cumulative_return"] for r in runs(folder)]
        if not values:
            raise SystemExit(f"{folder}: no finished runs (seed*/summary.json)")
        if len(values) ** args.seeds > MAX_DRAWS:
            raise SystemExit(
                f"{folder}: {len(values)}^{args.seeds} draws is over {MAX_DRAWS:,}; "
                "give fewer --seeds"
            )
        reach = share_reaching(values, bar, args.seeds)
        print(
            f"{folder}: {len(values)} runs, {args.seeds} drawn with replacement "
            f"({len(values) ** args.seeds} draws): mean >= bar in {100 * reach:.1f} %"
        )


if __name__ == "__main__":
    main()
