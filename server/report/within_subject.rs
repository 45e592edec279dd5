//! Rank tests for a within-subject study (the paper's Figures 4 and 6): every participant scored
//! every condition, so the scores form a participants × conditions matrix, and a participant is
//! compared only with themself.
//!
//! - [`complete_cases`]: a participant with any missing (or non-finite) score is dropped, and
//!   counted in [`WithinSubject::dropped`]; the tests below need complete rows.
//! - [`friedman`]: do the conditions differ at all? Ranks within each participant, chi-square
//!   statistic with the tie correction, df = k - 1; effect size Kendall's W.
//! - [`wilcoxon`]: which pairs differ? The signed-rank test on paired scores (two-sided, or
//!   one-sided [`Alternative::Greater`] for a paired test over seeds), zero differences dropped
//!   (Wilcoxon's method), average ranks for ties; effect size the matched-pairs rank-biserial
//!   correlation.
//! - [`holm`]: Holm's step-down correction over all pairs.
//! - [`within_subject`]: all of it for one matrix, with a [`WithinSubject::caution`] when there
//!   are too few participants for any pair to reach p < 0.05.
//!
//! Every number matches scipy 1.17 (`friedmanchisquare`, `wilcoxon(..., zero_method="wilcox",
//! correction=True)`) on the datasets of `benches/reference/within_subject_reference.py`.

use serde::Serialize;

use super::distributions::{chi_square_sf, normal_sf};

/// The largest number of non-zero differences for which [`wilcoxon`] enumerates the exact null
/// distribution (2^25 sign patterns, counted by a subset-sum table of 326 totals, not listed).
pub const EXACT_MAX_N: usize = 25;

/// The significance level the caution speaks of.
pub const ALPHA: f64 = 0.05;

/// The participants with a score for every condition, and who was left out.
#[derive(Clone, Debug, PartialEq)]
pub struct CompleteCases {
    /// One row per kept participant, `conditions` scores each.
    pub rows: Vec<Vec<f64>>,
    /// The index (into the input) of each kept participant.
    pub kept: Vec<usize>,
    /// The index of each dropped participant: a missing cell, a non-finite score, or a row
    /// of the wrong length.
    pub dropped: Vec<usize>,
    pub conditions: usize,
}

/// Keeps the participants with a finite score for each of the `conditions` conditions; the
/// rest are dropped, not imputed: a within-subject comparison of a participant who skipped a
/// condition has nothing to compare that condition with.
pub fn complete_cases(scores: &[Vec<Option<f64>>], conditions: usize) -> CompleteCases {
    let mut cases = CompleteCases {
        rows: Vec::new(),
        kept: Vec::new(),
        dropped: Vec::new(),
        conditions,
    };
    for (i, row) in scores.iter().enumerate() {
        let complete: Option<Vec<f64>> = if row.len() == conditions {
            row.iter().map(|s| s.filter(|v| v.is_finite())).collect()
        } else {
            None
        };
        match complete {
            Some(values) => {
                cases.rows.push(values);
                cases.kept.push(i);
            }
            None => cases.dropped.push(i),
        }
    }
    cases
}

/// Average ranks (1-based) of `values`, ties sharing the mean of the ranks they span, and the
/// size of each group of ties.
fn average_ranks(values: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut ties = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        // Ranks start + 1 ..= end, averaged.
        let rank = (start + 1 + end) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = rank;
        }
        ties.push(end - start);
        start = end;
    }
    (ranks, ties)
}

/// Σ (t³ - t) over groups of ties of sizes t: the ties' share of the rank variance.
fn tie_sum(ties: &[usize]) -> f64 {
    ties.iter().map(|&t| (t * t * t - t) as f64).sum()
}

/// The Friedman test's result.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Friedman {
    /// The chi-square statistic, tie-corrected.
    pub statistic: f64,
    /// k - 1.
    pub df: usize,
    /// P(chi-square(df) ≥ statistic).
    pub p: f64,
    /// Kendall's coefficient of concordance, statistic / (n (k - 1)), in [0, 1]: 0 when the
    /// conditions' rank sums are equal, 1 when every participant ranks them alike. With ties it
    /// is the tie-corrected W, since the statistic is.
    pub kendall_w: f64,
    /// Participants.
    pub n: usize,
    /// Conditions.
    pub k: usize,
}

/// The Friedman test over complete rows (participants) of k ≥ 2 scores each. `None` without
/// two conditions and a participant, or when every participant scored every condition alike
/// (no ranks to compare; scipy returns NaN there).
///
/// With R_j the rank sum of condition j, ranks taken within each participant:
/// statistic = (12 / (n k (k + 1)) Σ R_j² - 3 n (k + 1)) / C, where the tie correction is
/// C = 1 - Σ (t³ - t) / (n k (k² - 1)) over every participant's groups of ties.
pub fn friedman(rows: &[Vec<f64>]) -> Option<Friedman> {
    let n = rows.len();
    let k = rows.first().map_or(0, Vec::len);
    if n == 0 || k < 2 {
        return None;
    }
    assert!(
        rows.iter().all(|r| r.len() == k),
        "friedman needs complete rows of equal length"
    );
    let mut rank_sums = vec![0.0; k];
    let mut ties = 0.0;
    for row in rows {
        let (ranks, groups) = average_ranks(row);
        for (sum, rank) in rank_sums.iter_mut().zip(ranks) {
            *sum += rank;
        }
        ties += tie_sum(&groups);
    }
    let (nf, kf) = (n as f64, k as f64);
    let correction = 1.0 - ties / (nf * kf * (kf * kf - 1.0));
    if correction <= 0.0 {
        return None;
    }
    let squares: f64 = rank_sums.iter().map(|r| r * r).sum();
    let statistic =
        ((12.0 / (nf * kf * (kf + 1.0)) * squares - 3.0 * nf * (kf + 1.0)) / correction).max(0.0);
    Some(Friedman {
        statistic,
        df: k - 1,
        p: chi_square_sf(statistic, (k - 1) as f64),
        kendall_w: statistic / (nf * (kf - 1.0)),
        n,
        k,
    })
}

/// Which difference a [`wilcoxon`] test looks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Alternative {
    /// x and y differ, either way.
    TwoSided,
    /// x lies above y (e.g. a method's result above a baseline's, paired by seed).
    Greater,
}

/// How a [`wilcoxon`] p-value was computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WilcoxonMethod {
    /// Counting sign patterns: at most [`EXACT_MAX_N`] non-zero differences, none tied.
    Exact,
    /// The normal approximation with tie and continuity correction.
    Normal,
}

/// The Wilcoxon signed-rank test's result for x against y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Wilcoxon {
    pub alternative: Alternative,
    /// As scipy reports it: min(R+, R-) for two-sided, R+ for greater.
    pub statistic: f64,
    /// The rank sum of the positive differences x - y.
    pub r_plus: f64,
    /// The rank sum of the negative differences.
    pub r_minus: f64,
    /// Pairs whose difference is not zero: the sample size the test has.
    pub n: usize,
    /// Pairs with a zero difference, dropped.
    pub zeros: usize,
    pub method: WilcoxonMethod,
    /// The continuity-corrected z of the normal approximation; `None` for the exact test.
    pub z: Option<f64>,
    pub p: f64,
    /// The matched-pairs rank-biserial correlation (R+ - R-) / (R+ + R-), in [-1, 1]: positive
    /// when x tends to lie above y, 1 when every non-zero difference is positive; 0 without
    /// non-zero differences.
    pub rank_biserial: f64,
}

/// The Wilcoxon signed-rank test on the paired differences x_i - y_i.
///
/// Zero differences are dropped (Wilcoxon's method); the remaining |differences| are ranked,
/// ties sharing average ranks. With at most [`EXACT_MAX_N`] of them and no ties the p-value is
/// exact, from the distribution of R+ over all 2^n sign patterns; otherwise it is the normal
/// approximation z = (R+ - n (n + 1) / 4 ∓ 1/2) / σ, with
/// σ² = n (n + 1) (2n + 1) / 24 - Σ (t³ - t) / 48. Two-sided p-values are twice the smaller
/// tail, at most 1. Inputs must be finite.
///
/// # Panics
/// If `x` and `y` differ in length.
pub fn wilcoxon(x: &[f64], y: &[f64], alternative: Alternative) -> Wilcoxon {
    assert_eq!(x.len(), y.len(), "wilcoxon needs paired samples");
    let differences: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    let non_zero: Vec<f64> = differences.iter().copied().filter(|d| *d != 0.0).collect();
    let n = non_zero.len();
    let magnitudes: Vec<f64> = non_zero.iter().map(|d| d.abs()).collect();
    let (ranks, ties) = average_ranks(&magnitudes);
    let r_plus: f64 = (0..n)
        .filter(|&i| non_zero[i] > 0.0)
        .map(|i| ranks[i])
        .sum();
    let r_minus: f64 = (0..n)
        .filter(|&i| non_zero[i] < 0.0)
        .map(|i| ranks[i])
        .sum();
    let tied = ties.iter().any(|&t| t > 1);

    let (method, z, p) = if n <= EXACT_MAX_N && !tied {
        // No ties: the ranks are 1..=n and R+ a whole number.
        let r = r_plus.round() as usize;
        let counts = signed_rank_counts(n);
        let total: f64 = counts.iter().sum();
        let at_least = counts[r..].iter().sum::<f64>() / total;
        let at_most = counts[..=r].iter().sum::<f64>() / total;
        let p = match alternative {
            Alternative::Greater => at_least,
            Alternative::TwoSided => (2.0 * at_least.min(at_most)).min(1.0),
        };
        (WilcoxonMethod::Exact, None, p)
    } else {
        let nf = n as f64;
        let mean = nf * (nf + 1.0) / 4.0;
        let sd = ((nf * (nf + 1.0) * (2.0 * nf + 1.0) - tie_sum(&ties) / 2.0) / 24.0).sqrt();
        let raw = (r_plus - mean) / sd;
        let (z, p) = match alternative {
            Alternative::Greater => {
                let z = raw - 0.5 / sd;
                (z, normal_sf(z))
            }
            Alternative::TwoSided => {
                let z = raw - raw.signum() * 0.5 / sd;
                (z, (2.0 * normal_sf(z.abs())).min(1.0))
            }
        };
        (WilcoxonMethod::Normal, Some(z), p)
    };
    let statistic = match alternative {
        Alternative::TwoSided => r_plus.min(r_minus),
        Alternative::Greater => r_plus,
    };
    let rank_sum = r_plus + r_minus;
    Wilcoxon {
        alternative,
        statistic,
        r_plus,
        r_minus,
        n,
        zeros: differences.len() - n,
        method,
        z,
        p,
        rank_biserial: if rank_sum > 0.0 {
            (r_plus - r_minus) / rank_sum
        } else {
            0.0
        },
    }
}

/// The one-sided test that x lies above y: [`wilcoxon`] with [`Alternative::Greater`].
pub fn wilcoxon_greater(x: &[f64], y: &[f64]) -> Wilcoxon {
    wilcoxon(x, y, Alternative::Greater)
}

/// counts[s]: how many of the 2^n subsets of the ranks 1..=n sum to s, i.e. how many sign
/// patterns give R+ = s (exact in f64: at most 2^25).
fn signed_rank_counts(n: usize) -> Vec<f64> {
    let max = n * (n + 1) / 2;
    let mut counts = vec![0.0; max + 1];
    counts[0] = 1.0;
    for rank in 1..=n {
        for s in (rank..=max).rev() {
            counts[s] += counts[s - rank];
        }
    }
    counts
}

/// The smallest p-value the exact signed-rank test can give with n non-zero differences:
/// every difference on one side, 2 / 2^n two-sided, 1 / 2^n for greater.
pub fn smallest_exact_p(n: usize, alternative: Alternative) -> f64 {
    let one_tail = 0.5f64.powi(n as i32);
    match alternative {
        Alternative::TwoSided => (2.0 * one_tail).min(1.0),
        Alternative::Greater => one_tail,
    }
}

/// Holm's step-down adjustment of m p-values, in their input order: sorted ascending, the
/// i-th smallest (from 0) becomes max over j ≤ i of min(1, (m - j) p_(j)). Rejecting where the
/// adjusted p is below α controls the family-wise error rate at α.
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut adjusted = vec![0.0; m];
    let mut running = 0.0f64;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p[i]).min(1.0));
        adjusted[i] = running;
    }
    adjusted
}

/// One pair of conditions, compared.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PairwiseWilcoxon {
    /// Condition indices, a < b; the test is of a's scores against b's (a positive
    /// rank-biserial correlation: a scored higher).
    pub a: usize,
    pub b: usize,
    pub test: Wilcoxon,
    /// The test's p after Holm's correction over all k (k - 1) / 2 pairs.
    pub p_holm: f64,
}

/// The analysis of one participants × conditions matrix.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WithinSubject {
    pub conditions: usize,
    /// Participants with every score, the n of every test.
    pub participants: usize,
    /// Participants dropped for a missing score ([`complete_cases`]).
    pub dropped: usize,
    /// `None` if it cannot be computed (see [`friedman`]).
    pub friedman: Option<Friedman>,
    /// Every pair (a, b), a < b, in order (0, 1), (0, 2), ..., (1, 2), ...
    pub pairs: Vec<PairwiseWilcoxon>,
    /// Set when there are too few participants for the pairwise tests to mean much.
    pub caution: Option<String>,
}

/// Friedman, pairwise two-sided Wilcoxon tests with Holm's correction, effect sizes and a
/// caution, for a matrix of scores (rows: participants; columns: the `conditions` conditions;
/// `None`: missing).
pub fn within_subject(scores: &[Vec<Option<f64>>], conditions: usize) -> WithinSubject {
    let cases = complete_cases(scores, conditions);
    let k = cases.conditions;
    let column = |j: usize| -> Vec<f64> { cases.rows.iter().map(|r| r[j]).collect() };
    let mut pairs: Vec<PairwiseWilcoxon> = Vec::new();
    for a in 0..k {
        for b in a + 1..k {
            pairs.push(PairwiseWilcoxon {
                a,
                b,
                test: wilcoxon(&column(a), &column(b), Alternative::TwoSided),
                p_holm: f64::NAN,
            });
        }
    }
    let raw: Vec<f64> = pairs.iter().map(|pair| pair.test.p).collect();
    for (pair, adjusted) in pairs.iter_mut().zip(holm(&raw)) {
        pair.p_holm = adjusted;
    }
    let n = cases.rows.len();
    WithinSubject {
        conditions: k,
        participants: n,
        dropped: cases.dropped.len(),
        friedman: friedman(&cases.rows),
        caution: caution(n, pairs.len()),
        pairs,
    }
}

/// A warning when n participants cannot give any of `pairs` pairwise two-sided tests a p below
/// [`ALPHA`]: before Holm's correction (the exact test's floor 2 / 2^n, so n < 6), or after it
/// (that floor times the number of pairs, e.g. n = 6 with three conditions). With ties the
/// normal approximation can dip below the exact floor, but at such sizes it is not to be
/// trusted, and the caution says so.
pub fn caution(n: usize, pairs: usize) -> Option<String> {
    if n == 0 {
        return Some("no participant has a score for every condition".to_string());
    }
    let floor = smallest_exact_p(n, Alternative::TwoSided);
    let participants = if n == 1 {
        "participant"
    } else {
        "participants"
    };
    let ties =
        "(with ties the normal approximation is used instead, which is unreliable at this size)";
    if floor >= ALPHA {
        return Some(format!(
            "with n = {n} {participants} the smallest two-sided Wilcoxon p is {floor}; \
             no pair can reach {ALPHA} {ties}"
        ));
    }
    let holm_floor = (floor * pairs as f64).min(1.0);
    if holm_floor >= ALPHA {
        return Some(format!(
            "with n = {n} {participants} the smallest two-sided Wilcoxon p is {floor}, \
             {holm_floor} after Holm's correction over {pairs} pairs; no pair can reach {ALPHA} \
             after correction {ties}"
        ));
    }
    None
}

#[cfg(test)]
#[path = "within_subject_tests.rs"]
mod tests;
