"""Figure 5's alignment curves with DRPL's variants beside the paper's DRPL (issue 38): per task,
alignment (mean over posterior samples of cos(theta, theta_true)) against queries asked,
mean +- s.e. over seeds, one line per series.

    python3 benches/reference/fig5_curves.py --root docs/results/fig5 --queries 40 \
        --out docs/results/fig5/ablations/fig5-variants-40.svg

Reads the run folders' `alignment.csv` (row 0 is the prior, row q the posterior after q
queries). A series is `LABEL=GRID:METHOD`, GRID a folder relative to ROOT ("." for the
committed grid); the defaults per `--queries` are in `SERIES`. Needs matplotlib.
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TASKS: list[tuple[str, str]] = [
    ("lunar-lander", "Lunar Lander"),
    ("reaching", "Reaching"),
    ("placing", "Placing"),
]

SERIES: dict[int, list[str]] = {
    20: [
        "DRPL (paper)=ablations/queries-20:drpl",
        "DRPL-MI=ablations/drpl-mi-queries-20:drpl",
        "DRPL-SS=ablations/queries-20:drpl-ss",
        "Random fragment=ablations/queries-20:fragment",
        "Full trajectory=ablations/queries-20:full",
    ],
    40: [
        "DRPL (paper)=.:drpl",
        "DRPL-MI=ablations/drpl-mi:drpl",
        "DRPL-SS=.:drpl-ss",
        "Random fragment=.:fragment",
        "Full trajectory=.:full",
        "DRPL-SS, MI=ablations/mi-baselines:drpl-ss",
        "Random fragment, MI=ablations/mi-baselines:fragment",
    ],
    80: [
        "DRPL (paper)=ablations/queries-80:drpl",
        "DRPL-MI=ablations/drpl-mi-queries-80:drpl",
        "DRPL-SS=ablations/queries-80:drpl-ss",
        "Random fragment=ablations/queries-80:fragment",
        "Full trajectory=ablations/queries-80:full",
    ],
}


def curves(folder: Path) -> list[list[float]]:
    """One alignment curve per finished seed (those with a summary.json)."""
    out: list[list[float]] = []
    for seed in sorted(folder.glob("seed*")):
        if not (seed / "summary.json").exists():
            continue
        with open(seed / "alignment.csv", newline="") as f:
            out.append([float(row["alignment"]) for row in csv.DictReader(f)])
    return out


def mean_se(column: list[float]) -> tuple[float, float]:
    m = statistics.fmean(column)
    se = statistics.stdev(column) / math.sqrt(len(column)) if len(column) > 1 else 0.0
    return m, se


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=Path("docs/results/fig5"))
    parser.add_argument("--queries", type=int, default=40, choices=sorted(SERIES))
    parser.add_argument("--series", nargs="*", help="LABEL=GRID:METHOD (default: SERIES[queries])")
    parser.add_argument("--out", type=Path, required=True, help=".svg or .png")
    args = parser.parse_args()
    series = args.series or SERIES[args.queries]
    fig, axes = plt.subplots(1, len(TASKS), figsize=(5 * len(TASKS), 4), sharey=True)
    for ax, (task, title) in zip(axes, TASKS):
        for spec in series:
            label, where = spec.split("=", 1)
            grid, method = where.split(":")
            runs = curves(args.root / grid / task / method)
            if not runs:
                continue
            n = min(len(c) for c in runs)
            stats = [mean_se([c[q] for c in runs]) for q in range(n)]
            xs = list(range(n))
            m = [s[0] for s in stats]
            se = [s[1] for s in stats]
            style = "--" if label.endswith(", MI") else "-"
            (line,) = ax.plot(xs, m, style, label=f"{label} ({len(runs)} seeds)", lw=1.6)
            ax.fill_between(xs, [a - b for a, b in zip(m, se)], [a + b for a, b in zip(m, se)],
                            color=line.get_color(), alpha=0.18, lw=0)
        ax.set_title(title)
        ax.set_xlabel("queries")
        ax.grid(alpha=0.3)
        ax.axhline(0.85, color="grey", lw=0.8, ls=":")
    axes[0].set_ylabel("alignment (mean ± s.e. over seeds)")
    axes[-1].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(args.out)


if __name__ == "__main__":
    main()
