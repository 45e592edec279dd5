#!/usr/bin/env python3
"""What Lunar Lander's scene graph tells of how a descent ends, from `dualrep sim --steps` (every
step of a noisy heuristic's episodes, with the product's abstract state). For each way of
cutting steps into cells it prints the share of the label's entropy the cell carries (plug-in,
pooled steps; biased up for many small cells) and the held-out AUC of the cell's failure share as
a score (fitted on the episodes of even seeds, scored on the odd ones and the other way round,
averaged) (docs/results/lunar-graph-outcomes/README.md).

    dualrep sim --task lunar-lander --episodes 2000 --noise 0.5 --noise-correlation 0.95 \
        --steps steps.csv
    python3 benches/grids/graph_outcomes.py steps.csv [--before 55] [--skip 5] \
        [--align end|touchdown] [--question outcome|moment]

Two questions, over the episodes that landed or failed (time-limit episodes left out):
`outcome` tells a window's steps (from `before` to `skip` steps before the episode's end, or
before its first leg contact) of failed episodes from those of landed ones; `moment` tells a
failed episode's window before touchdown from every other step of flight, as a query rule that
meant to ask before failures would have to. The cuts: the graph's abstract state; the graph and
one more predicate, falling speed above its median over the steps; falling speed alone in as
many equal-count bins as the graph fills; and the graph's height bits alone.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import struct
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path

from rows import midranks


@dataclass
class Step:
    seed: int
    state: str
    fall_speed: float
    label: bool


def episodes_of(path: Path) -> dict[int, list[dict[str, str]]]:
    episodes: dict[int, list[dict[str, str]]] = defaultdict(list)
    with path.open() as f:
        for row in csv.DictReader(f):
            episodes[int(row["seed"])].append(row)
    return episodes


def touchdown(rows: list[dict[str, str]]) -> int | None:
    """The first step on which a leg touches (`obs_6` or `obs_7`), or the last step if the episode
    failed on the ground without one; None if it ended off the screen (|x| >= 1), which is no
    descent."""
    for i, row in enumerate(rows):
        if row["obs_6"] != "0" or row["obs_7"] != "0":
            return i
    return None if abs(float(rows[-1]["obs_0"])) >= 1.0 else len(rows) - 1


def labelled_steps(
    episodes: dict[int, list[dict[str, str]]], before: int, skip: int, align: str, question: str
) -> list[Step]:
    """The steps the question is asked of, each labelled True for a failure.

    `outcome`: the steps t with anchor - before <= t < anchor - skip of every episode that landed
    or failed, labelled by how it ended. The anchor is the episode's end or (`align` touchdown) its
    first leg contact: a landing's last half second is spent at rest (the rest rule asks 25 steps
    without engines), which an end-anchored window compares with a failure's flight.
    `moment`: every step before touchdown of every episode that landed or failed, labelled True
    in a failed episode's window (anchored at touchdown): can the cell pick out the moments
    before a failure among all the moments of flight, as a query rule would have to?"""
    steps: list[Step] = []
    for seed, rows in episodes.items():
        outcome = rows[-1]["outcome"]
        if outcome not in ("success", "failure"):
            continue
        touch = touchdown(rows)
        anchor = len(rows) if align == "end" and question == "outcome" else touch
        if anchor is None:
            continue
        failed = outcome == "failure"
        first, last = max(0, anchor - before), max(0, anchor - skip)
        span = range(first, last) if question == "outcome" else range(anchor)
        for t in span:
            row = rows[t]
            label = failed and (question == "outcome" or first <= t < last)
            steps.append(Step(seed, row["abstract_state"], float(row["obs_3"]), label))
    return steps


def endings(episodes: dict[int, list[dict[str, str]]]) -> Counter[str]:
    counts: Counter[str] = Counter(rows[-1]["outcome"] for rows in episodes.values())
    counts["off the screen"] = sum(
        rows[-1]["outcome"] == "failure" and touchdown(rows) is None for rows in episodes.values()
    )
    return counts


def entropy(p: float) -> float:
    return 0.0 if p in (0.0, 1.0) else -(p * math.log2(p) + (1 - p) * math.log2(1 - p))


def information_share(cells: list[str], failed: list[bool]) -> float:
    """I(outcome; cell) / H(outcome), plug-in over the pooled steps."""
    total = len(cells)
    base = entropy(sum(failed) / total)
    by_cell: dict[str, list[bool]] = defaultdict(list)
    for c, y in zip(cells, failed):
        by_cell[c].append(y)
    conditional = sum(len(ys) / total * entropy(sum(ys) / len(ys)) for ys in by_cell.values())
    return (base - conditional) / base if base > 0 else 0.0


def held_out_auc(cells: list[str], failed: list[bool], seeds: list[int]) -> float:
    """The AUC of each cell's failure share (fitted on one half of the episodes, with one prior
    step at the fitted half's base rate) as a score for the other half's steps; both ways,
    averaged."""
    aucs = []
    for fit_parity in (0, 1):
        fit = [(c, y) for c, y, s in zip(cells, failed, seeds) if s % 2 == fit_parity]
        base = sum(y for _, y in fit) / len(fit)
        counts: dict[str, list[float]] = defaultdict(lambda: [base, 1.0])
        for c, y in fit:
            counts[c][0] += y
            counts[c][1] += 1
        scored = [
            (counts[c][0] / counts[c][1] if c in counts else base, y)
            for c, y, s in zip(cells, failed, seeds)
            if s % 2 != fit_parity
        ]
        aucs.append(auc([score for score, _ in scored], [y for _, y in scored]))
    return sum(aucs) / len(aucs)


def rule_scores(checkpoint: Path, dim: int) -> tuple[dict[str, float], dict[str, float], float]:
    """The DREF rule's UCB and mean |H - H_hat| per abstract state (as bit strings of `dim`
    predicates, predicate 0 first) in a `train` run checkpoint, and the score of a state never
    answered. The file is
    `dualrep-run/1\n`, a u64 LE length and the run's state as JSON, then the learner and replay
    (core/src/guidance/run_checkpoint.rs)."""
    data = checkpoint.read_bytes()
    magic = b"dualrep-run/1\n"
    if not data.startswith(magic):
        raise SystemExit(f"{checkpoint}: not a dualrep run checkpoint")
    (length,) = struct.unpack_from("<Q", data, len(magic))
    start = len(magic) + 8
    state = json.loads(data[start : start + length])
    rule = state["schedule"].get("dref")
    if rule is None:
        raise SystemExit(f"{checkpoint}: its run has no DREF rule")
    total, c, form = rule["total"], rule["c"], rule["form"]

    def ucb(count: int, mean_error: float) -> float:
        if form == "authors":
            return mean_error + c * math.sqrt(2 * total / (count + 1))
        return math.inf if count == 0 else mean_error + c * math.sqrt(2 * math.log(total) / count)

    scores, errors = {}, {}
    for key, stats in rule["stats"].items():
        bits = "".join("1" if (int(key) >> i) & 1 else "0" for i in range(dim))
        scores[bits] = ucb(stats["count"], stats["mean_error"])
        errors[bits] = stats["mean_error"]
    return scores, errors, ucb(0, 0.0)


def auc(scores: list[float], labels: list[bool]) -> float:
    """Mann-Whitney's U of the labelled steps' scores over the others', over the pairs, from
    midranks (rows.py's pairwise u_statistic is quadratic, too slow for this many steps)."""
    ranks = midranks(scores)
    n_true = sum(labels)
    u = sum(r for r, y in zip(ranks, labels) if y) - n_true * (n_true + 1) / 2
    return u / (n_true * (len(labels) - n_true))


def equal_count_bins(values: list[float], bins: int) -> list[str]:
    order = sorted(values)
    edges = [order[len(order) * i // bins] for i in range(1, bins)]
    return [str(sum(v >= e for e in edges)) for v in values]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("steps", type=Path, help="a `dualrep sim --steps` file (Lunar Lander)")
    parser.add_argument("--before", type=int, default=55, help="window start, steps before the end")
    parser.add_argument("--skip", type=int, default=5, help="steps left out at the very end")
    parser.add_argument(
        "--align",
        choices=("end", "touchdown"),
        default="end",
        help="count the window back from the episode's end or from its first leg contact "
        "(failures off the screen left out)",
    )
    parser.add_argument(
        "--question",
        choices=("outcome", "moment"),
        default="outcome",
        help="outcome: tell the window's steps of failed episodes from landed ones'; moment: "
        "tell the window's steps of failed episodes from every other step of flight",
    )
    parser.add_argument(
        "--rule-from",
        type=Path,
        metavar="CHECKPOINT",
        help="also score every step by the DREF rule's UCB (and its mean |H - H_hat| alone) of "
        "its abstract state in this `train` run checkpoint: their AUC, nothing fitted",
    )
    args = parser.parse_args()
    if not 0 <= args.skip < args.before:
        parser.error(f"--skip {args.skip} must be at least 0 and below --before {args.before}")

    episodes = episodes_of(args.steps)
    ends = endings(episodes)
    ended = ends["success"] + ends["failure"]
    print(
        f"episodes: {len(episodes)} ({ends['success']} landed, {ends['failure']} failed, "
        f"{ends['time_limit']} time limit); of those that landed or failed, "
        f"{ends['failure'] / ended:.3f} failed; {ends['off the screen']} of the failures off the "
        "screen (no touchdown: left out where the window is anchored at one)"
    )
    steps = labelled_steps(episodes, args.before, args.skip, args.align, args.question)
    failed = [s.label for s in steps]
    seeds = [s.seed for s in steps]
    anchor = "touchdown" if args.question == "moment" else args.align
    print(
        f"question: {args.question}; window: steps {args.before} to {args.skip} before the "
        f"{anchor}; {len(steps)} steps, {sum(failed) / len(steps):.3f} of them labelled failure"
    )
    graph = [s.state for s in steps]
    median = sorted(s.fall_speed for s in steps)[len(steps) // 2]
    graph_speed = [f"{s.state}{int(s.fall_speed > median)}" for s in steps]
    filled = len(set(graph))
    speed_bins = equal_count_bins([s.fall_speed for s in steps], filled)
    # Bits 3-5: above the flags (twice, one per flag) and above the pad's level.
    height = [s.state[3:6] for s in steps]
    print("| cut | cells | label entropy carried | held-out AUC |")
    print("|---|---:|---:|---:|")
    for name, cells in (
        ("the scene graph", graph),
        (f"the graph + falling speed above its median ({median:.3f})", graph_speed),
        ("falling speed alone, equal-count bins", speed_bins),
        ("the graph's height bits alone", height),
    ):
        print(
            f"| {name} | {len(set(cells))} | {information_share(cells, failed):.3f} "
            f"| {held_out_auc(cells, failed, seeds):.3f} |"
        )
    if args.rule_from:
        scores, errors, unanswered = rule_scores(args.rule_from, len(steps[0].state))
        ucb = [scores.get(s.state, unanswered) for s in steps]
        # A state never answered has no error of its own: it ranks below every answered one.
        error = [errors.get(s.state, -1.0) for s in steps]
        answered = sum(s.state in scores for s in steps) / len(steps)
        print(
            f"\nthe rule at {args.rule_from.name}: {answered:.3f} of the steps are in states it has "
            f"answered; {unanswered:.1f} is the score of a state never answered"
        )
        print("| the rule's | AUC, all steps |")
        print("|---|---:|")
        print(f"| UCB | {auc(ucb, failed):.3f} |")
        print(f"| mean \\|H - H_hat\\| alone | {auc(error, failed):.3f} |")


if __name__ == "__main__":
    main()
