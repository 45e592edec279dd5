"""Paired comparisons of Figure 5's runs (issue 38): DRPL (or a variant of it) against each
baseline, seed by seed, with a one-sided Wilcoxon signed-rank test (H1: DRPL > baseline).

    python3 benches/reference/fig5_paired.py --root docs/results/fig5 > paired.md

Reads only the run folders' `summary.json` (final alignment, theta_true, pool size and mean
segment length) and `queries.jsonl` (the clips each query showed), under

    ROOT/<task>/<method>/seed<S>/                  the committed grid (40 queries)
    ROOT/ablations/<name>/<task>/<method>/seed<S>/ one ablation grid each

and prints Markdown tables to stdout:

1. every grid's final alignment per task and method (mean +- s.e. over its seeds);
2. the paired tests: for each task and each comparison in `COMPARISONS`, the per-seed
   difference d_s = alignment(DRPL row, seed s) - alignment(baseline, seed s), its mean +- s.e.,
   the number of seeds DRPL wins, and scipy's `wilcoxon(d, alternative="greater")` p (exact for
   20 seeds without ties or zeros; zeros are dropped, scipy's default `zero_method="wilcox"`);
3. the lengths (steps) of the clips the queries showed, per grid, task and method;
4. how far apart the two clips of a query are in the belief's (standardised) features, and the
   true reward gap the oracle answers on, per grid, task and method; DRPL's by predicate.

Before pairing, it checks that the two runs of a seed drew the same true reward (theta_true
equal) and, where the two grids segment alike, the same trajectories (the pool's segment count
and mean segment length equal); a pair that fails the check stops the script.

Needs scipy (a throwaway venv: `python3 -m venv /tmp/venv-drpl && /tmp/venv-drpl/bin/pip
install scipy`).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
from dataclasses import dataclass
from pathlib import Path

from scipy.stats import wilcoxon

TASKS: list[str] = ["lunar-lander", "reaching", "placing"]
BASELINES: list[str] = ["drpl-ss", "fragment", "full"]
METHODS: list[str] = ["drpl", *BASELINES]


@dataclass(frozen=True)
class Comparison:
    """One row of the paired table: `drpl_grid`'s DRPL against `base_grid`'s baselines."""

    label: str
    drpl_grid: str  # "" for the committed grid, else the ablation's folder name
    base_grid: str
    same_segments: bool = True  # both grids segment the trajectories alike (same min_run)


COMPARISONS: list[Comparison] = [
    Comparison("DRPL (paper), 40 queries", "", ""),
    Comparison("DRPL-MI, 40 queries", "drpl-mi", ""),
    Comparison("DRPL-MI vs MI baselines, 40 queries", "drpl-mi", "mi-baselines"),
    Comparison("DRPL (paper), 20 queries", "queries-20", "queries-20"),
    Comparison("DRPL-MI, 20 queries", "drpl-mi-queries-20", "queries-20"),
    Comparison("DRPL (paper), 80 queries", "queries-80", "queries-80"),
    Comparison("DRPL-MI, 80 queries", "drpl-mi-queries-80", "queries-80"),
    Comparison("DRPL (paper), seeds 20-39", "seeds-20-39", "seeds-20-39"),
    Comparison("DRPL-MI, seeds 20-39", "drpl-mi-seeds-20-39", "seeds-20-39"),
    Comparison("DRPL (paper), samples = 400", "samples-400", "samples-400"),
    Comparison("DRPL (paper), burn_in = 1000", "burn_in-1000", "burn_in-1000"),
    Comparison("DRPL (paper), proposal_std = 0.2", "proposal_std-0.2", "proposal_std-0.2"),
    Comparison("DRPL (paper), min_run = 1", "min_run-1", "min_run-1"),
    Comparison("DRPL (paper), min_run = 5", "min_run-5", "min_run-5"),
    Comparison("DRPL (paper), min_run = 8", "min_run-8", "min_run-8"),
]


@dataclass(frozen=True)
class Run:
    seed: int
    alignment: float
    theta_true: tuple[float, ...]
    segments: int
    mean_segment_length: float
    queries: int


def grid_dir(root: Path, grid: str) -> Path:
    return root if grid == "" else root / "ablations" / grid


def load_runs(root: Path, grid: str, task: str, method: str) -> dict[int, Run]:
    """The finished runs (those with a summary.json) of one grid, task and method, by seed."""
    runs: dict[int, Run] = {}
    folder = grid_dir(root, grid) / task / method
    for summary in sorted(folder.glob("seed*/summary.json")):
        s = json.loads(summary.read_text())
        runs[int(s["seed"])] = Run(
            seed=int(s["seed"]),
            alignment=float(s["final_alignment"]),
            theta_true=tuple(s["theta_true"]),
            segments=int(s["segments"]),
            mean_segment_length=float(s["mean_segment_length"]),
            queries=int(s["queries"]),
        )
    return runs


def mean_se(xs: list[float]) -> tuple[float, float]:
    if len(xs) < 2:
        return (xs[0] if xs else math.nan, math.nan)
    return statistics.fmean(xs), statistics.stdev(xs) / math.sqrt(len(xs))


def fmt(xs: list[float], digits: int = 3) -> str:
    m, se = mean_se(xs)
    return f"{m:.{digits}f} ± {se:.{digits}f}"


def fmt_p(p: float) -> str:
    return f"{p:.1e}" if p < 0.001 else f"{p:.3f}"


def grids_present(root: Path) -> list[str]:
    ablations = root / "ablations"
    names = sorted(p.name for p in ablations.iterdir() if p.is_dir()) if ablations.is_dir() else []
    return ["", *names]


def alignment_table(root: Path) -> list[str]:
    out = ["| Grid | Task | " + " | ".join(METHODS) + " | Seeds |", "|---|---|" + "---:|" * 5]
    for grid in grids_present(root):
        for task in TASKS:
            cells: list[str] = []
            seeds: set[int] = set()
            for method in METHODS:
                runs = load_runs(root, grid, task, method)
                seeds |= set(runs)
                cells.append(fmt([r.alignment for r in runs.values()]) if runs else "")
            if seeds:
                name = grid or "committed (40 queries)"
                out.append(f"| {name} | {task} | " + " | ".join(cells) + f" | {len(seeds)} |")
    return out


def paired_table(root: Path) -> list[str]:
    out = [
        "| Task | DRPL row | Baseline | DRPL | Baseline | Mean difference | Wins | Wilcoxon p (one-sided) | Seeds |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for task in TASKS:
        for c in COMPARISONS:
            drpl = load_runs(root, c.drpl_grid, task, "drpl")
            if not drpl:
                continue
            for base in BASELINES:
                other = load_runs(root, c.base_grid, task, base)
                seeds = sorted(set(drpl) & set(other))
                if not seeds:
                    continue
                for s in seeds:
                    a, b = drpl[s], other[s]
                    if a.theta_true != b.theta_true:
                        raise SystemExit(f"{task} seed {s}: theta_true differs ({c.label}, {base})")
                    if c.same_segments and (
                        a.segments != b.segments or a.mean_segment_length != b.mean_segment_length
                    ):
                        raise SystemExit(f"{task} seed {s}: pools differ ({c.label}, {base})")
                d = [drpl[s].alignment - other[s].alignment for s in seeds]
                wins = sum(x > 0 for x in d)
                p = wilcoxon(d, alternative="greater").pvalue
                base_name = base + ("-mi" if c.base_grid == "mi-baselines" else "")
                out.append(
                    f"| {task} | {c.label} | {base_name} | "
                    f"{fmt([drpl[s].alignment for s in seeds])} | "
                    f"{fmt([other[s].alignment for s in seeds])} | {fmt(d)} | "
                    f"{wins}/{len(seeds)} | {fmt_p(p)}{' *' if p < 0.05 else ''} | {len(seeds)} |"
                )
    return out


def quantile(xs: list[int], q: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * (len(s) - 1) + 0.5))]


def segment_table(root: Path, grids: list[str]) -> list[str]:
    """Lengths (end - start, steps) of the clips shown, both sides of every query of every seed,
    and the pool's mean segment length (summary.json), per grid, task and method."""
    out = [
        "| Grid | Task | Method | Clips | Mean | s.d. | Min | 10 % | Median | 90 % | Max | Pool's mean segment length |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for grid in grids:
        for task in TASKS:
            for method in METHODS:
                folder = grid_dir(root, grid) / task / method
                lengths: list[int] = []
                for q in sorted(folder.glob("seed*/queries.jsonl")):
                    for line in q.read_text().splitlines():
                        row = json.loads(line)
                        lengths += [row[side]["end"] - row[side]["start"] for side in ("left", "right")]
                if not lengths:
                    continue
                pool = [r.mean_segment_length for r in load_runs(root, grid, task, method).values()]
                out.append(
                    f"| {grid or 'committed'} | {task} | {method} | {len(lengths)} | "
                    f"{statistics.fmean(lengths):.1f} | {statistics.stdev(lengths):.1f} | "
                    f"{min(lengths)} | {quantile(lengths, 0.1):.0f} | {quantile(lengths, 0.5):.0f} | "
                    f"{quantile(lengths, 0.9):.0f} | {max(lengths)} | {fmt(pool, 1)} |"
                )
    return out


def feature_gap_table(root: Path, grids: list[str]) -> list[str]:
    """How far apart the two clips of a query are in the features the belief sees (the
    standardised `features` of queries.jsonl): ||phi_a - phi_b|| over every query of every seed,
    and |theta_true . (phi_a - phi_b)|, the true reward gap the oracle answers on."""
    out = [
        "| Grid | Task | Method | Queries | Mean norm of feature difference | Median | Mean true reward gap |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for grid in grids:
        for task in TASKS:
            for method in METHODS:
                norms: list[float] = []
                gaps: list[float] = []
                for seed in sorted((grid_dir(root, grid) / task / method).glob("seed*")):
                    if not (seed / "summary.json").exists():
                        continue
                    theta = json.loads((seed / "summary.json").read_text())["theta_true"]
                    for line in (seed / "queries.jsonl").read_text().splitlines():
                        q = json.loads(line)
                        d = [a - b for a, b in zip(q["left"]["features"], q["right"]["features"])]
                        norms.append(math.sqrt(sum(x * x for x in d)))
                        gaps.append(abs(sum(t * x for t, x in zip(theta, d))))
                if norms:
                    out.append(
                        f"| {grid or 'committed'} | {task} | {method} | {len(norms)} | "
                        f"{statistics.fmean(norms):.2f} | {statistics.median(norms):.2f} | "
                        f"{statistics.fmean(gaps):.2f} |"
                    )
    return out


def predicate_table(root: Path, grids: list[str]) -> list[str]:
    """DRPL's queries by the cycled predicate they differ in: how many, and their mean norm of
    feature difference (as in `feature_gap_table`)."""
    out = ["| Grid | Task | Predicate | Queries | Mean norm of feature difference |", "|---|---|---|---:|---:|"]
    for grid in grids:
        for task in TASKS:
            by: dict[str, list[float]] = {}
            for seed in sorted((grid_dir(root, grid) / task / "drpl").glob("seed*")):
                if not (seed / "summary.json").exists():
                    continue
                for line in (seed / "queries.jsonl").read_text().splitlines():
                    q = json.loads(line)
                    d = [a - b for a, b in zip(q["left"]["features"], q["right"]["features"])]
                    by.setdefault(str(q["predicate"]), []).append(math.sqrt(sum(x * x for x in d)))
            for pred, norms in by.items():
                out.append(
                    f"| {grid or 'committed'} | {task} | {pred} | {len(norms)} | {statistics.fmean(norms):.2f} |"
                )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=Path("docs/results/fig5"))
    parser.add_argument(
        "--segment-grids",
        default=",drpl-mi,min_run-1,min_run-8",
        help="comma-separated grids for the clip-length table ('' = the committed grid)",
    )
    args = parser.parse_args()
    print("### Final alignment per grid (mean ± s.e. over seeds)\n")
    print("\n".join(alignment_table(args.root)))
    print("\n### Paired: DRPL row minus baseline, per seed (one-sided Wilcoxon, * p < 0.05)\n")
    print("\n".join(paired_table(args.root)))
    print("\n### Lengths of the clips shown (steps), all queries and seeds\n")
    print("\n".join(segment_table(args.root, args.segment_grids.split(","))))
    print("\n### How far apart the two clips of a query are (standardised features)\n")
    print("\n".join(feature_gap_table(args.root, ["", "drpl-mi", "mi-baselines"])))
    print("\n### DRPL's queries by predicate\n")
    print("\n".join(predicate_table(args.root, ["", "drpl-mi"])))


if __name__ == "__main__":
    main()
