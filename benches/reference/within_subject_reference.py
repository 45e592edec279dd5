"""Reference values for server/report/within_subject.rs, from scipy.

    python3 -m venv /tmp/venv-scipy && /tmp/venv-scipy/bin/pip install scipy
    /tmp/venv-scipy/bin/python benches/reference/within_subject_reference.py

For each dataset (participants x conditions, k = 3): the Friedman test, Kendall's W, and the
pairwise two-sided Wilcoxon signed-rank tests with Holm's correction; plus one-sided
("greater") tests over seeds. The Wilcoxon method follows the Rust rule: exact when at most 25
non-zero differences and no ties among their absolute values, else the normal approximation
with tie and continuity correction; zeros are dropped (zero_method="wilcox") either way. The
printed lines are pasted into the tests of within_subject.rs.
"""

import itertools

import numpy as np
import scipy
from scipy import stats

DATASETS = {
    # n = 6, no ties within a participant nor among any pair's |differences|.
    "N6_NO_TIES": [
        [3.1, 4.7, 5.2],
        [2.4, 3.9, 3.5],
        [4.0, 6.2, 5.1],
        [1.5, 2.3, 4.6],
        [3.3, 3.0, 4.4],
        [2.8, 4.1, 5.9],
    ],
    # n = 6, 7-point Likert answers: ties within participants and zero differences.
    "N6_LIKERT": [
        [3, 5, 6],
        [4, 4, 5],
        [2, 5, 5],
        [3, 6, 7],
        [5, 4, 6],
        [3, 3, 3],
    ],
    # n = 12, no ties.
    "N12_NO_TIES": [
        [12.5, 14.1, 17.3],
        [10.2, 13.8, 12.8],
        [11.7, 11.1, 15.4],
        [9.4, 12.6, 13.0],
        [13.3, 15.9, 16.2],
        [8.8, 9.5, 11.6],
        [12.1, 10.7, 14.8],
        [10.9, 13.4, 12.3],
        [11.2, 14.6, 18.1],
        [9.9, 12.0, 10.3],
        [13.6, 16.7, 15.5],
        [10.4, 11.9, 13.7],
    ],
    # n = 12, Likert: ties and zeros.
    "N12_LIKERT": [
        [2, 4, 5],
        [3, 3, 6],
        [4, 5, 5],
        [1, 4, 4],
        [3, 5, 7],
        [5, 4, 6],
        [2, 2, 3],
        [4, 6, 6],
        [3, 5, 4],
        [2, 3, 5],
        [4, 4, 4],
        [3, 6, 5],
    ],
}

# One-sided "greater" tests, x against y paired by seed.
GREATER = {
    "SEEDS_EXACT": (
        [0.82, 0.75, 0.92, 0.68, 0.88, 0.79, 0.85],
        [0.71, 0.77, 0.80, 0.62, 0.74, 0.70, 0.86],
    ),
    "SEEDS_TIES": (
        [5, 6, 4, 7, 6, 5, 8, 6, 5, 7],
        [4, 5, 4, 5, 6, 3, 6, 4, 6, 5],
    ),
    # 30 seeds, no ties: past 25 the normal approximation even without ties.
    "SEEDS_LARGE": (
        [i if i % 4 else -i for i in range(1, 31)],
        [0] * 30,
    ),
}


def rule(d):
    """The Rust crate's method choice: exact iff <= 25 non-zero |d| and none tied."""
    nz = np.abs(d[d != 0])
    return "exact" if len(nz) <= 25 and len(np.unique(nz)) == len(nz) else "approx"


def wilcoxon(x, y, alternative):
    x, y = np.asarray(x, float), np.asarray(y, float)
    d = x - y
    method = rule(d)
    r = stats.wilcoxon(x, y, zero_method="wilcox", correction=True,
                       alternative=alternative, method=method)
    nz = d[d != 0]
    ranks = stats.rankdata(np.abs(nz))
    r_plus, r_minus = ranks[nz > 0].sum(), ranks[nz < 0].sum()
    rbc = (r_plus - r_minus) / (r_plus + r_minus) if len(nz) else 0.0
    return method, float(r.statistic), float(r.pvalue), float(rbc), len(nz)


def holm(p):
    m = len(p)
    order = np.argsort(p, kind="stable")
    adj, running = np.empty(m), 0.0
    for i, j in enumerate(order):
        running = max(running, min(1.0, (m - i) * p[j]))
        adj[j] = running
    return adj


print(f"# scipy {scipy.__version__}, numpy {np.__version__}")
for name, data in DATASETS.items():
    data = np.asarray(data, float)
    n, k = data.shape
    f = stats.friedmanchisquare(*data.T)
    w = f.statistic / (n * (k - 1))
    print(f"{name}: friedman statistic = {f.statistic:.12f}, p = {f.pvalue:.12e}, W = {w:.12f}")
    pairs = list(itertools.combinations(range(k), 2))
    results = [wilcoxon(data[:, a], data[:, b], "two-sided") for a, b in pairs]
    adj = holm(np.array([r[2] for r in results]))
    for (a, b), (method, stat, p, rbc, used), ph in zip(pairs, results, adj):
        print(f"  ({a}, {b}) {method:6s} n = {used:2d}: T = {stat:.1f}, p = {p:.12e}, "
              f"holm = {ph:.12e}, rank-biserial = {rbc:.12f}")
for name, (x, y) in GREATER.items():
    method, stat, p, rbc, used = wilcoxon(x, y, "greater")
    print(f"{name} greater {method} n = {used}: R+ = {stat:.1f}, p = {p:.12e}, "
          f"rank-biserial = {rbc:.12f}")
