//! The one-sided Mann-Whitney U test over seeds: is method A's result above method B's more
//! often than chance would have it? Exact: the p-value counts, among all ways of splitting the
//! pooled results into groups of A's and B's sizes, those whose rank sum for A is at least the
//! observed one (ties get mid-ranks). With a handful of seeds per method a normal approximation
//! would be off, and the exact count is cheap (a subset-sum over at most a few hundred rank
//! totals).

use serde::Serialize;

/// The test's result for "A above B".
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MannWhitney {
    /// U of A: pairs (a, b) with a > b, ties counted half.
    pub u: f64,
    /// P(U >= observed) when A's and B's results come from one distribution.
    pub p_one_sided: f64,
    pub n_a: usize,
    pub n_b: usize,
}

/// The one-sided exact Mann-Whitney U test that `a` lies above `b`; `None` if either is empty.
pub fn mann_whitney_greater(a: &[f64], b: &[f64]) -> Option<MannWhitney> {
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let u: f64 = a
        .iter()
        .map(|x| {
            b.iter()
                .map(|y| match x.partial_cmp(y) {
                    Some(std::cmp::Ordering::Greater) => 1.0,
                    Some(std::cmp::Ordering::Equal) => 0.5,
                    _ => 0.0,
                })
                .sum::<f64>()
        })
        .sum();
    // Twice the mid-ranks of the pooled sample: whole numbers, so rank sums can index a table.
    let pooled: Vec<f64> = a.iter().chain(b).copied().collect();
    let doubled_ranks: Vec<usize> = pooled
        .iter()
        .map(|x| {
            let below = pooled.iter().filter(|y| *y < x).count();
            let equal = pooled.iter().filter(|y| *y == x).count();
            // Ranks below + 1 ..= below + equal; twice their mean.
            2 * below + equal + 1
        })
        .collect();
    let observed: usize = doubled_ranks[..a.len()].iter().sum();
    let total: usize = doubled_ranks.iter().sum();
    // ways[c][s]: subsets of c of the items seen so far whose doubled ranks sum to s.
    let mut ways = vec![vec![0f64; total + 1]; a.len() + 1];
    ways[0][0] = 1.0;
    for &r in &doubled_ranks {
        for c in (1..=a.len()).rev() {
            for s in (r..=total).rev() {
                ways[c][s] += ways[c - 1][s - r];
            }
        }
    }
    let all: f64 = ways[a.len()].iter().sum();
    let at_least: f64 = ways[a.len()][observed..].iter().sum();
    Some(MannWhitney {
        u,
        p_one_sided: at_least / all,
        n_a: a.len(),
        n_b: b.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn complete_separation_has_the_smallest_p() {
        // 5 against 5, every A above every B: 1 / C(10, 5) = 1 / 252.
        let t =
            mann_whitney_greater(&[6.0, 7.0, 8.0, 9.0, 10.0], &[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(t.u, 25.0);
        assert!(close(t.p_one_sided, 1.0 / 252.0));
        // The other way round every split is at least as extreme.
        let t =
            mann_whitney_greater(&[1.0, 2.0, 3.0, 4.0, 5.0], &[6.0, 7.0, 8.0, 9.0, 10.0]).unwrap();
        assert_eq!(t.u, 0.0);
        assert!(close(t.p_one_sided, 1.0));
    }

    #[test]
    fn matches_scipy_on_small_samples() {
        // scipy.stats.mannwhitneyu([3, 5, 8, 9], [1, 2, 4, 6, 7], alternative="greater",
        // method="exact"): U = 15, p = 0.1428571 (18 of the 126 splits reach rank sum 25).
        let t = mann_whitney_greater(&[3.0, 5.0, 8.0, 9.0], &[1.0, 2.0, 4.0, 6.0, 7.0]).unwrap();
        assert_eq!(t.u, 15.0);
        assert!(
            (t.p_one_sided - 18.0 / 126.0).abs() < 1e-12,
            "{}",
            t.p_one_sided
        );
    }

    #[test]
    fn ties_count_half_and_identical_samples_are_not_significant() {
        let t = mann_whitney_greater(&[0.0, 0.0, 1.0], &[0.0, 0.0, 0.0]).unwrap();
        // Each A zero ties the three B zeros (1.5), the A one beats all three (3).
        assert_eq!(t.u, 6.0);
        let same = mann_whitney_greater(&[2.0; 4], &[2.0; 4]).unwrap();
        assert_eq!(same.u, 8.0);
        assert!(close(same.p_one_sided, 1.0));
        assert!(mann_whitney_greater(&[], &[1.0]).is_none());
    }
}
