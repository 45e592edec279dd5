//! How much trainers agree. Evaluative answers (+1 / 0 / -1) are ordinal ratings:
//! Krippendorff's alpha with the ordinal metric (Krippendorff 2011, "Computing Krippendorff's
//! Alpha-Reliability"), which takes any number of trainers per query and missing answers.
//! Preference answers are choices among categories (left, right, about equal): Fleiss' kappa
//! (Fleiss 1971), in its form for a varying number of raters per unit (each unit's observed
//! agreement over its own rater pairs; category shares over all ratings), which is Fleiss' own
//! when every unit has the same number. Pure.
//!
//! Both are `None` where they are undefined: fewer than two answers to any one query, or no
//! variation at all to expect disagreement from (every answer the same).

use std::collections::BTreeMap;

/// How distances between two values count (Krippendorff's difference functions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Equal or not.
    Nominal,
    /// Ranks: the distance is how many values lie between, by their frequencies.
    Ordinal,
    /// Squared difference of the values.
    Interval,
}

/// Krippendorff's alpha over `units`, each the values its coders gave (one per coder; a unit
/// with fewer than two values has no pair to compare and is left out).
pub fn krippendorff_alpha(units: &[Vec<f64>], metric: Metric) -> Option<f64> {
    let pairable: Vec<&Vec<f64>> = units.iter().filter(|u| u.len() >= 2).collect();
    // The distinct values, in order, as indices.
    let mut values: Vec<f64> = pairable.iter().flat_map(|u| u.iter().copied()).collect();
    values.sort_by(f64::total_cmp);
    values.dedup();
    let index = |v: f64| values.iter().position(|x| *x == v).expect("a known value");
    let k = values.len();
    if k == 0 {
        return None;
    }
    // The coincidence matrix: every ordered pair of values within a unit, weighted 1/(m - 1).
    let mut o = vec![vec![0.0f64; k]; k];
    for u in &pairable {
        let m = u.len() as f64;
        for (i, a) in u.iter().enumerate() {
            for (j, b) in u.iter().enumerate() {
                if i != j {
                    o[index(*a)][index(*b)] += 1.0 / (m - 1.0);
                }
            }
        }
    }
    let n_c: Vec<f64> = o.iter().map(|row| row.iter().sum()).collect();
    let n: f64 = n_c.iter().sum();
    let delta = |c: usize, d: usize| -> f64 {
        match metric {
            Metric::Nominal => f64::from(u8::from(c != d)),
            Metric::Interval => (values[c] - values[d]).powi(2),
            Metric::Ordinal => {
                let (lo, hi) = (c.min(d), c.max(d));
                let between: f64 = n_c[lo..=hi].iter().sum();
                (between - (n_c[lo] + n_c[hi]) / 2.0).powi(2)
            }
        }
    };
    let (mut observed, mut expected) = (0.0, 0.0);
    for c in 0..k {
        for d in 0..k {
            let dist = delta(c, d);
            observed += o[c][d] * dist;
            expected += n_c[c] * n_c[d] * dist;
        }
    }
    if expected <= 0.0 || n <= 1.0 {
        return None;
    }
    Some(1.0 - (n - 1.0) * observed / expected)
}

/// Fleiss' kappa over `units`, each the categories its raters chose (a unit with fewer than
/// two ratings is left out).
pub fn fleiss_kappa<C: Ord + Clone>(units: &[Vec<C>]) -> Option<f64> {
    let rated: Vec<&Vec<C>> = units.iter().filter(|u| u.len() >= 2).collect();
    if rated.is_empty() {
        return None;
    }
    let mut totals: BTreeMap<C, f64> = BTreeMap::new();
    let mut observed = 0.0;
    for u in &rated {
        let mut counts: BTreeMap<&C, f64> = BTreeMap::new();
        for c in u.iter() {
            *counts.entry(c).or_default() += 1.0;
            *totals.entry(c.clone()).or_default() += 1.0;
        }
        let n = u.len() as f64;
        let agreeing: f64 = counts.values().map(|x| x * (x - 1.0)).sum();
        observed += agreeing / (n * (n - 1.0));
    }
    observed /= rated.len() as f64;
    let all: f64 = totals.values().sum();
    let expected: f64 = totals.values().map(|x| (x / all).powi(2)).sum();
    if expected >= 1.0 {
        return None;
    }
    Some((observed - expected) / (1.0 - expected))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Krippendorff (2011), section C: four observers, twelve units, values 1-5, missing data.
    fn reliability_data() -> Vec<Vec<f64>> {
        let nan = f64::NAN;
        let observers = [
            [1., 2., 3., 3., 2., 1., 4., 1., 2., nan, nan, nan],
            [1., 2., 3., 3., 2., 2., 4., 1., 2., 5., nan, 3.],
            [nan, 3., 3., 3., 2., 3., 4., 2., 2., 5., 1., nan],
            [1., 2., 3., 3., 2., 4., 4., 1., 2., 5., 1., nan],
        ];
        (0..12)
            .map(|u| {
                observers
                    .iter()
                    .map(|o| o[u])
                    .filter(|v| !v.is_nan())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn alpha_matches_krippendorffs_worked_example() {
        // His paper gives 0.743, 0.815 and 0.849; the places beyond are the `krippendorff`
        // package's (PyPI, 0.8) on the same data.
        let data = reliability_data();
        let close = |metric, expected: f64| {
            let a = krippendorff_alpha(&data, metric).unwrap();
            assert!((a - expected).abs() < 1e-9, "{metric:?}: {a} vs {expected}");
        };
        close(Metric::Nominal, 0.743421052631579);
        close(Metric::Ordinal, 0.8153875037548814);
        close(Metric::Interval, 0.8491071428571428);
    }

    #[test]
    fn alpha_is_one_for_perfect_agreement_and_undefined_without_variation() {
        let agree = vec![vec![1.0, 1.0], vec![-1.0, -1.0], vec![0.0, 0.0, 0.0]];
        assert_eq!(krippendorff_alpha(&agree, Metric::Ordinal), Some(1.0));
        assert_eq!(krippendorff_alpha(&[vec![1.0, 1.0]], Metric::Ordinal), None);
        assert_eq!(
            krippendorff_alpha(&[vec![1.0], vec![-1.0]], Metric::Ordinal),
            None
        );
        // Systematic disagreement is below zero.
        let opposed = vec![vec![1.0, -1.0], vec![-1.0, 1.0], vec![1.0, -1.0]];
        assert!(krippendorff_alpha(&opposed, Metric::Ordinal).unwrap() < 0.0);
    }

    #[test]
    fn ordinal_alpha_counts_near_misses_less_than_far_ones() {
        let near = vec![
            vec![1.0, 0.0],
            vec![-1.0, -1.0],
            vec![1.0, 1.0],
            vec![0.0, 0.0],
        ];
        let far = vec![
            vec![1.0, -1.0],
            vec![-1.0, -1.0],
            vec![1.0, 1.0],
            vec![0.0, 0.0],
        ];
        let (a_near, a_far) = (
            krippendorff_alpha(&near, Metric::Ordinal).unwrap(),
            krippendorff_alpha(&far, Metric::Ordinal).unwrap(),
        );
        assert!(a_near > a_far, "{a_near} vs {a_far}");
    }

    #[test]
    fn kappa_matches_fleiss_worked_example() {
        // Wikipedia's "Fleiss' kappa" example: 10 subjects, 14 raters, 5 categories; 0.210.
        let counts = [
            [0, 0, 0, 0, 14],
            [0, 2, 6, 4, 2],
            [0, 0, 3, 5, 6],
            [0, 3, 9, 2, 0],
            [2, 2, 8, 1, 1],
            [7, 7, 0, 0, 0],
            [3, 2, 6, 3, 0],
            [2, 5, 3, 2, 2],
            [6, 5, 2, 1, 0],
            [0, 2, 2, 3, 7],
        ];
        let units: Vec<Vec<usize>> = counts
            .iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .flat_map(|(c, n)| std::iter::repeat_n(c, *n))
                    .collect()
            })
            .collect();
        // statsmodels' `fleiss_kappa` on the same table: 0.20993070442195522.
        let kappa = fleiss_kappa(&units).unwrap();
        assert!((kappa - 0.20993070442195522).abs() < 1e-12, "{kappa}");
    }

    #[test]
    fn kappa_is_one_for_agreement_and_undefined_for_a_single_category() {
        let agree = vec![vec!["left", "left"], vec!["right", "right"]];
        assert_eq!(fleiss_kappa(&agree), Some(1.0));
        assert_eq!(fleiss_kappa(&[vec!["left", "left"]]), None);
        assert_eq!(fleiss_kappa::<&str>(&[vec!["left"]]), None);
        let opposed = vec![vec!["left", "right"], vec!["right", "left"]];
        assert!(fleiss_kappa(&opposed).unwrap() < 0.0);
    }
}
