#!/usr/bin/env python3
"""How a method's runs learnt over time: per seed, the mean episode return and the queries asked
in each stretch of steps, and the step at which the run first "learnt" by the report's rule over
a rolling 10 episodes (8 of 10 succeed; on Lunar Lander their mean return is 200 or more).

    python3 benches/grids/curves.py docs/results/fig3-lunar-lander-150k/lunar-lander/dref \
        [--bin 15000]

A folder holds `seed<N>/` runs (metrics.csv: one row per episode with its end step, return,
outcome and the run's feedback count so far; learner.csv, where the run has one: the means of
each episode's updates, binned the same way; answers.csv, where the run has one: the share of
its answers in each stretch that were +1). A cumulative reward says how much a run earned;
this says when: a run that learns late earns little even if it ends learnt.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

from rows import episodes_learnt


def episodes(run: Path) -> list[dict[str, str]]:
    with open(run / "metrics.csv") as f:
        return list(csv.DictReader(f))


def first_learnt(rows: list[dict[str, str]], lunar_lander: bool) -> int | None:
    """The end step of the first episode after which the last 10 pass the report's rule."""
    for i in range(9, len(rows)):
        if episodes_learnt(rows[i - 9 : i + 1], lunar_lander):
            return int(rows[i]["step"])
    return None


def binned(rows: list[dict[str, str]], width: int) -> list[tuple[float | None, int]]:
    """Per stretch of `width` steps: the mean return of the episodes that ended in it, and the
    queries asked by its last episode's end since the stretch before."""
    if not rows:
        return []
    end = int(rows[-1]["step"])
    out: list[tuple[float | None, int]] = []
    asked_before = 0
    for start in range(0, end, width):
        inside = [e for e in rows if start < int(e["step"]) <= start + width]
        mean = sum(float(e["return"]) for e in inside) / len(inside) if inside else None
        asked = int(inside[-1]["feedback_count"]) if inside else asked_before
        out.append((mean, asked - asked_before))
        asked_before = asked
    return out


def side_rows(run: Path, name: str) -> list[dict[str, str]]:
    """The run's per-episode file `name` beside metrics.csv (learner.csv: binaries of 7b894c2c or
    later; answers.csv, the answers by sign: the twenty-seventh session's or later), or nothing."""
    path = run / name
    if not path.exists():
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def binned_learner(rows: list[dict[str, str]], column: str, width: int) -> list[float | None]:
    """Per stretch of `width` steps: the mean of `column` over the updates of the episodes that
    ended in it (each episode's mean weighted by its updates)."""
    end = int(rows[-1]["step"])
    out: list[float | None] = []
    for start in range(0, end, width):
        inside = [r for r in rows if start < int(r["step"]) <= start + width and r[column] != ""]
        updates = sum(int(r["updates"]) for r in inside)
        out.append(
            sum(float(r[column]) * int(r["updates"]) for r in inside) / updates if updates else None
        )
    return out


def binned_good_share(rows: list[dict[str, str]], width: int) -> list[float | None]:
    """Per stretch of `width` steps: the share of the answers given in the episodes that ended
    in it that were +1 (`None` where nothing was asked)."""
    end = int(rows[-1]["step"])
    out: list[float | None] = []
    for start in range(0, end, width):
        inside = [r for r in rows if start < int(r["step"]) <= start + width]
        asked = sum(int(r["asked"]) for r in inside)
        out.append(sum(int(r["good"]) for r in inside) / asked if asked else None)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--bin", type=int, default=15000, help="steps a stretch (15000)")
    args = parser.parse_args()
    seeds = sorted(args.folder.glob("seed*"), key=lambda p: int(p.name[4:]))
    for run in seeds:
        rows = episodes(run)
        if not rows:
            continue
        lunar_lander = json.loads((run / "config.json").read_text())["task"] == "lunar-lander"
        bins = binned(rows, args.bin)
        returns = " ".join("   -  " if m is None else f"{m:6.0f}" for m, _ in bins)
        asked = " ".join(f"{a:6d}" for _, a in bins)
        at = first_learnt(rows, lunar_lander)
        print(f"{run.name}: first learnt at {'never' if at is None else f'{at} steps'}")
        print(f"  mean return a {args.bin}-step stretch: {returns}")
        print(f"  queries asked in it:                 {asked}")
        learner = side_rows(run, "learner.csv")
        if learner:
            for column in ("critic_loss", "actor_loss", "human_critic_loss", "ent_coef"):
                means = " ".join(
                    "   -  " if m is None else f"{m:6.3g}" for m in binned_learner(learner, column, args.bin)
                )
                print(f"  {column + ', its mean:':<36} {means}")
        answers = side_rows(run, "answers.csv")
        if answers:
            shares = " ".join(
                "   -  " if m is None else f"{m:6.2f}" for m in binned_good_share(answers, args.bin)
            )
            print(f"  {'answers that were +1, their share:':<36} {shares}")


if __name__ == "__main__":
    main()
