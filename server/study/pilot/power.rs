//! Power by resampling a pool of simulated participants: for each study size n, many simulated
//! studies of n participants drawn from the pool, and the share of them in which the main
//! contrast comes out significant.
//!
//! - **Bootstrap** (the headline): n participants drawn from the pool *with* replacement, so any
//!   n can be asked of any pool. It treats the pool as the population, which makes it optimistic
//!   when the pool is small (the pool's own quirks count as the effect), and a participant drawn
//!   twice gives tied differences, which moves the Wilcoxon test from its exact distribution to
//!   the normal approximation.
//! - **Subsample**: n *distinct* participants of the pool (only where n <= the pool's size):
//!   no repeated participant, but at n = pool size every simulated study is the whole pool, so
//!   its share is 0 or 1.
//!
//! The test is the two-sided Wilcoxon signed-rank test on the two conditions' paired scores
//! ([`wilcoxon`]: exact without ties up to 25 pairs, else the normal approximation with tie and
//! continuity correction, zero differences dropped, as scipy), significant when p < alpha.
//! With three or more conditions the Friedman test's share is reported beside it.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::report::within_subject::{Alternative, friedman, smallest_exact_p, wilcoxon};

/// Separates the resampling's random stream from the teachers' and the orderings'.
const RESAMPLE_SALT: u64 = 0x5e5a_3b1e_0000_0000;

/// What to estimate: the studies' sizes, how many simulated studies per size, the level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PowerPlan {
    pub ns: Vec<usize>,
    pub studies: usize,
    pub alpha: f64,
    pub seed: u64,
}

/// The share of simulated studies that came out significant, with its Monte-Carlo standard
/// error sqrt(share (1 - share) / studies).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Share {
    pub power: f64,
    pub mc_se: f64,
    pub studies: usize,
}

impl Share {
    fn of(significant: usize, studies: usize) -> Self {
        let power = significant as f64 / studies as f64;
        Share {
            power,
            mc_se: (power * (1.0 - power) / studies as f64).sqrt(),
            studies,
        }
    }
}

/// One study size's estimates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PowerRow {
    pub n: usize,
    /// Wilcoxon on the main contrast, participants drawn with replacement.
    pub bootstrap: Share,
    /// Wilcoxon on the main contrast, n distinct participants; `None` when n > the pool.
    pub subsample: Option<Share>,
    /// Friedman over all conditions, with replacement; `None` with two conditions.
    pub friedman_bootstrap: Option<Share>,
    /// Friedman over all conditions, n distinct participants.
    pub friedman_subsample: Option<Share>,
    /// The smallest p the exact two-sided Wilcoxon test can give with n pairs (2 / 2^n): at
    /// or above alpha, no study of this size can come out significant without ties.
    pub exact_p_floor: f64,
    /// How many different sets of n participants the pool has (C(pool, n), saturating): the
    /// subsample's studies are drawn from these.
    pub distinct_subsets: Option<u64>,
}

/// How to draw one simulated study's participants.
#[derive(Clone, Copy)]
enum Draw {
    WithReplacement,
    Distinct,
}

/// The estimates for each n of `plan`, from `scores` (one row per pool participant, one score
/// per condition) and the main contrast's two columns `contrast`.
///
/// # Panics
/// On an empty pool, rows of unequal length or a contrast column out of range.
pub fn estimate(scores: &[Vec<f64>], contrast: [usize; 2], plan: &PowerPlan) -> Vec<PowerRow> {
    let pool = scores.len();
    let k = scores.first().map_or(0, Vec::len);
    assert!(pool > 0, "an empty pool has no power to estimate");
    assert!(scores.iter().all(|r| r.len() == k), "ragged score matrix");
    assert!(contrast.iter().all(|&c| c < k), "contrast out of range");
    plan.ns
        .iter()
        .map(|&n| {
            let mut rng = ChaCha8Rng::seed_from_u64(plan.seed ^ RESAMPLE_SALT);
            rng.set_stream(n as u64);
            let bootstrap = simulate(scores, contrast, n, plan, Draw::WithReplacement, &mut rng);
            let subsample =
                (n <= pool).then(|| simulate(scores, contrast, n, plan, Draw::Distinct, &mut rng));
            PowerRow {
                n,
                bootstrap: bootstrap.0,
                subsample: subsample.map(|s| s.0),
                friedman_bootstrap: bootstrap.1,
                friedman_subsample: subsample.and_then(|s| s.1),
                exact_p_floor: smallest_exact_p(n, Alternative::TwoSided),
                distinct_subsets: (n <= pool).then(|| binomial(pool as u64, n as u64)),
            }
        })
        .collect()
}

/// `plan.studies` simulated studies of n participants: the Wilcoxon share and (k >= 3) the
/// Friedman share.
fn simulate(
    scores: &[Vec<f64>],
    [a, b]: [usize; 2],
    n: usize,
    plan: &PowerPlan,
    draw: Draw,
    rng: &mut ChaCha8Rng,
) -> (Share, Option<Share>) {
    let k = scores[0].len();
    let (mut wilcoxon_hits, mut friedman_hits) = (0, 0);
    let mut picked = Vec::with_capacity(n);
    let mut deck: Vec<usize> = (0..scores.len()).collect();
    for _ in 0..plan.studies {
        picked.clear();
        match draw {
            Draw::WithReplacement => {
                picked.extend((0..n).map(|_| rng.random_range(0..scores.len())));
            }
            Draw::Distinct => {
                // The first n of a partial Fisher-Yates shuffle.
                for i in 0..n {
                    let j = rng.random_range(i..deck.len());
                    deck.swap(i, j);
                }
                picked.extend_from_slice(&deck[..n]);
            }
        }
        let x: Vec<f64> = picked.iter().map(|&p| scores[p][a]).collect();
        let y: Vec<f64> = picked.iter().map(|&p| scores[p][b]).collect();
        if wilcoxon(&x, &y, Alternative::TwoSided).p < plan.alpha {
            wilcoxon_hits += 1;
        }
        if k >= 3 {
            let rows: Vec<Vec<f64>> = picked.iter().map(|&p| scores[p].clone()).collect();
            if friedman(&rows).is_some_and(|f| f.p < plan.alpha) {
                friedman_hits += 1;
            }
        }
    }
    (
        Share::of(wilcoxon_hits, plan.studies),
        (k >= 3).then(|| Share::of(friedman_hits, plan.studies)),
    )
}

/// C(n, r), saturating at `u64::MAX`.
fn binomial(n: u64, r: u64) -> u64 {
    let r = r.min(n - r);
    let mut c: u128 = 1;
    for i in 0..r {
        c = c * u128::from(n - i) / u128::from(i + 1);
        if c > u128::from(u64::MAX) {
            return u64::MAX;
        }
    }
    c as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, Normal};

    /// A pool of `pool` participants, two conditions: b = a + effect + noise.
    fn pool(pool: usize, effect: f64, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let person = Normal::new(100.0, 30.0).unwrap();
        let noise = Normal::new(0.0, 10.0).unwrap();
        (0..pool)
            .map(|_| {
                let a: f64 = person.sample(&mut rng);
                vec![a, a + effect + noise.sample(&mut rng)]
            })
            .collect()
    }

    fn plan(ns: &[usize]) -> PowerPlan {
        PowerPlan {
            ns: ns.to_vec(),
            studies: 400,
            alpha: 0.05,
            seed: 1,
        }
    }

    #[test]
    fn a_huge_effect_is_found_almost_always_from_n_6_on() {
        let scores = pool(16, 100.0, 0);
        let rows = estimate(&scores, [0, 1], &plan(&[4, 6, 8, 16]));
        // n = 4: the exact test cannot go below 2 / 16, ties or not at this size.
        assert_eq!(rows[0].exact_p_floor, 0.125);
        assert!(rows[0].bootstrap.power < 0.05, "{:?}", rows[0]);
        for row in &rows[1..] {
            assert!(row.bootstrap.power > 0.95, "{row:?}");
            assert!(row.subsample.unwrap().power > 0.95, "{row:?}");
        }
        let n8 = &rows[2];
        assert_eq!(n8.bootstrap.studies, 400);
        assert!(n8.bootstrap.mc_se < 0.02);
        assert_eq!(n8.distinct_subsets, Some(12_870));
        // At n = the pool, every subsample is the whole pool.
        assert_eq!(rows[3].distinct_subsets, Some(1));
        assert_eq!(rows[3].subsample.unwrap().power, 1.0);
        assert!(n8.friedman_bootstrap.is_none());
    }

    #[test]
    fn no_effect_is_found_about_alpha_of_the_time_or_less() {
        // A pool with no effect at all: each participant's difference has a mirror image.
        let half = pool(8, 0.0, 2);
        let mirrored = half.iter().map(|r| vec![r[0], r[0] - (r[1] - r[0])]);
        let scores: Vec<Vec<f64>> = half.iter().cloned().chain(mirrored).collect();
        for row in estimate(&scores, [0, 1], &plan(&[6, 8, 12])) {
            // Alpha, give or take the Monte-Carlo error (0.011 at 400 studies).
            assert!(row.bootstrap.power < 0.05 + 0.035, "{row:?}");
            assert!(row.subsample.unwrap().power < 0.05 + 0.035, "{row:?}");
        }
    }

    #[test]
    fn power_grows_with_n_for_a_moderate_effect() {
        let scores = pool(16, 8.0, 3);
        let rows = estimate(&scores, [0, 1], &plan(&[4, 6, 8, 12, 16, 24]));
        let powers: Vec<f64> = rows.iter().map(|r| r.bootstrap.power).collect();
        for w in powers.windows(2) {
            assert!(w[1] >= w[0] - 0.03, "{powers:?}");
        }
        assert!(powers[5] > powers[1] + 0.2, "{powers:?}");
        // Past the pool's size only the bootstrap has an answer.
        assert!(rows[5].subsample.is_none() && rows[5].distinct_subsets.is_none());
    }

    #[test]
    fn estimates_are_reproducible_and_friedman_joins_from_three_conditions() {
        let moderate = pool(10, 8.0, 4);
        let p = plan(&[6, 8]);
        let rows = estimate(&moderate, [0, 1], &p);
        assert_eq!(rows, estimate(&moderate, [0, 1], &p));
        assert_ne!(
            estimate(
                &moderate,
                [0, 1],
                &PowerPlan {
                    seed: 2,
                    ..p.clone()
                }
            ),
            rows
        );
        let mut scores = pool(10, 30.0, 4);
        for row in &mut scores {
            row.push(row[1] + 30.0);
        }
        let rows = estimate(&scores, [0, 2], &p);
        let f = rows[1].friedman_bootstrap.unwrap();
        assert!(f.power > 0.9, "{f:?}");
        assert!(rows[1].friedman_subsample.is_some());
    }

    #[test]
    fn binomials_saturate() {
        assert_eq!(binomial(16, 8), 12_870);
        assert_eq!(binomial(16, 16), 1);
        assert_eq!(binomial(16, 0), 1);
        assert_eq!(binomial(200, 100), u64::MAX);
    }
}
