#!/usr/bin/env python3
"""When Lunar Lander's learners take off against how many answers they had early: every finished
150k-step Lunar Lander run under a results folder that was answered on some steps but not all
(DREF in any form, EF below 100 %), one line each, ordered by the answers in its first 15k steps,
with the step at which it first learnt by the report's rule (`curves.first_learnt`), and EF-100's
runs for scale. Ends with Spearman's rank correlation between the early answers and the step of
take-off (a run that never learnt ranks after every run that did).

    python3 benches/grids/early_answers.py [docs/results]

A run copied into two grids (the same metrics.csv) is listed once. The profile column says which
oracle answered: the head's (alpha from 0.999) or the authors' runs as run (`as-run`, from 0.99).
"""

from __future__ import annotations

import hashlib
import json
import random
import sys
from pathlib import Path

from curves import episodes, first_learnt
from rows import mean_return, midranks

STEPS = 150_000
MARKS = (5_000, 15_000, 30_000)


def answered_by(rows: list[dict[str, str]], step: int) -> int:
    """The feedback count at the last episode end at or before `step`."""
    count = 0
    for row in rows:
        if int(row["step"]) > step:
            break
        count = int(row["feedback_count"])
    return count


def lunar_runs(root: Path) -> list[dict]:
    runs, seen = [], set()
    for summary_path in sorted(root.rglob("summary.json")):
        summary = json.loads(summary_path.read_text())
        if summary.get("task") != "lunar-lander" or summary.get("steps") != STEPS:
            continue
        if "feedback_fraction" not in summary or summary["feedback_fraction"] == 0:
            continue
        run = summary_path.parent
        digest = hashlib.sha256((run / "metrics.csv").read_bytes()).hexdigest()
        if digest in seen:
            continue
        seen.add(digest)
        rows = episodes(run)
        runs.append(
            {
                "run": str(run.relative_to(root)),
                "profile": "as-run" if summary["config"].get("oracle", {}).get("alpha0") == 0.99 else "head",
                "feedback": 100 * summary["feedback_fraction"],
                "reward": summary["cumulative_return"],
                "answered": [answered_by(rows, mark) for mark in MARKS],
                "learnt_at": first_learnt(rows, lunar_lander=True),
                "last10": mean_return(rows[-10:]),
            }
        )
    return runs


def spearman(x: list[float], y: list[float]) -> float:
    rx, ry = midranks(x), midranks(y)
    mx, my = sum(rx) / len(rx), sum(ry) / len(ry)
    cov = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    vx = sum((a - mx) ** 2 for a in rx)
    vy = sum((b - my) ** 2 for b in ry)
    return cov / (vx * vy) ** 0.5


def permutation_p(x: list[float], y: list[float], draws: int = 20_000) -> float:
    """One-sided: the share of random pairings whose rho is at most the observed one (more
    answers, earlier take-off), from a fixed generator so the output is the same every time."""
    observed = spearman(x, y)
    rng = random.Random(0)
    shuffled = list(y)
    at_most = 0
    for _ in range(draws):
        rng.shuffle(shuffled)
        at_most += spearman(x, shuffled) <= observed
    return (at_most + 1) / (draws + 1)


def line(r: dict) -> str:
    learnt = "never" if r["learnt_at"] is None else f"{r['learnt_at'] / 1000:.1f}k"
    answered = " ".join(f"{a:6d}" for a in r["answered"])
    return (
        f"{answered} {r['feedback']:6.2f} % {r['reward'] / 1000:7.1f}k {learnt:>7} "
        f"{r['last10']:7.1f}  {r['profile']:6} {r['run']}"
    )


def main() -> None:
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/results")
    runs = lunar_runs(root)
    header = " ".join(f"{'by ' + str(m // 1000) + 'k':>6}" for m in MARKS)
    print(f"{header} feedback   reward  learnt last 10  oracle run")
    partial = sorted((r for r in runs if r["feedback"] < 100), key=lambda r: r["answered"][1])
    for r in partial:
        print(line(r))
    print("EF-100 for scale:")
    for r in sorted((r for r in runs if r["feedback"] == 100), key=lambda r: r["run"]):
        print(line(r))
    never = STEPS + 1
    early = [float(r["answered"][1]) for r in partial]
    take_off = [float(never if r["learnt_at"] is None else r["learnt_at"]) for r in partial]
    print(
        f"{len(partial)} runs answered on some steps: Spearman's rho between answers in the first "
        f"15k steps and the step of take-off = {spearman(early, take_off):.2f} (one-sided "
        f"permutation p = {permutation_p(early, take_off):.3f})"
    )


if __name__ == "__main__":
    main()
