"""The side-by-side table of README.md: DREF, EF-100 and SAC on Gymnasium's Box2D Lunar
Lander through the env protocol (the run folders beside this file), on our rapier Lunar Lander
(../fig3/lunar-lander/) and stable-baselines3's SAC on Box2D (../lunar-lander-sb3/), with the
authors' figures after their first 20k steps (algorithms.md, section 2: true sums).

    python3 docs/results/lunar-lander-gymnasium/table.py
"""

from __future__ import annotations

import json
import statistics
from pathlib import Path
from typing import List, Optional

HERE = Path(__file__).resolve().parent
METHODS = [("dref", "DREF"), ("ef-100", "EF-100%"), ("sac", "SAC")]
# The authors' true cumulative reward after their first 20k steps (algorithms.md).
AUTHORS_20K = {"dref": "+8.1k", "ef-100": "+7.1k", "sac": "-5.5k"}


def summaries(folder: Path) -> List[dict]:
    return [json.loads(p.read_text()) for p in sorted(folder.glob("seed*/summary.json"))]


def k(x: float) -> str:
    return f"{x / 1000:+.1f}k"


def mean_se(values: List[float]) -> str:
    if not values:
        return "–"
    if len(values) == 1:
        return k(values[0])
    se = statistics.stdev(values) / len(values) ** 0.5
    return f"{k(statistics.mean(values))} ± {se / 1000:.1f}k"


def cell(runs: List[dict], seeds: Optional[int] = None) -> str:
    runs = runs[:seeds] if seeds else runs
    return f"{mean_se([r['cumulative_return'] for r in runs])} ({len(runs)})"


def feedback(runs: List[dict]) -> str:
    if not runs:
        return "–"
    return f"{100 * statistics.mean(r['feedback_fraction'] for r in runs):.1f} %"


def main() -> None:
    rows = [
        "| Method | Gymnasium Box2D, through the protocol | feedback | our rapier Lander | feedback | our rapier Lander, seeds 0-2 | authors, first 20k |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for method, name in METHODS:
        gym = summaries(HERE / method)
        ours = summaries(HERE.parent / "fig3" / "lunar-lander" / method)
        rows.append(
            f"| {name} | {cell(gym)} | {feedback(gym)} | {cell(ours)} | {feedback(ours)} | "
            f"{cell(ours, 3)} | {AUTHORS_20K[method]} |"
        )
    sb3 = [json.loads(p.read_text()) for p in sorted((HERE.parent / "lunar-lander-sb3").glob("seed*/summary.json"))]
    rows.append(f"| SAC, stable-baselines3 (Box2D, in-process) | {cell(sb3)} | – | | | | |")
    print("\n".join(rows))
    print()
    print("Cumulative reward after 20k steps: mean ± standard error over seeds (number of seeds).")


if __name__ == "__main__":
    main()
