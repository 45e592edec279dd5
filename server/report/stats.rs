//! Small statistics over seeds: mean and standard error, linear interpolation, even grids.
//!
//! The paper's figures show "the standard error of the means (n = 5)", i.e. the sample standard
//! deviation (Bessel-corrected) divided by sqrt(n); that is what [`mean_se`] returns.

use serde::Serialize;

/// Mean and standard error of the mean of a sample, with the sample size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeanSe {
    pub mean: f64,
    /// Sample standard deviation / sqrt(n); 0 for a single value (nothing to spread), NaN for none.
    pub se: f64,
    pub n: usize,
}

/// Mean and standard error of `values`. An empty sample gives NaN for both, so that a missing
/// method shows up as missing rather than as a plausible zero.
pub fn mean_se(values: &[f64]) -> MeanSe {
    let n = values.len();
    if n == 0 {
        return MeanSe {
            mean: f64::NAN,
            se: f64::NAN,
            n,
        };
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return MeanSe { mean, se: 0.0, n };
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    MeanSe {
        mean,
        se: (var / n as f64).sqrt(),
        n,
    }
}

/// `n` evenly spaced values from `start` to `end`, both included (`n >= 2`; `n == 1` gives
/// `[start]`).
pub fn linspace(start: f64, end: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![start],
        _ => (0..n)
            .map(|i| start + (end - start) * i as f64 / (n - 1) as f64)
            .collect(),
    }
}

/// The piecewise-linear curve through `points` (sorted by x, at least one) evaluated at `x`.
/// Outside the points the curve is held flat at its end values: a cumulative reward does not
/// change after the last finished episode, and before the first known point we have no slope.
pub fn interpolate(points: &[(f64, f64)], x: f64) -> f64 {
    let (first, last) = match (points.first(), points.last()) {
        (Some(f), Some(l)) => (*f, *l),
        _ => return f64::NAN,
    };
    if x <= first.0 {
        return first.1;
    }
    if x >= last.0 {
        return last.1;
    }
    // The first point strictly right of x; its predecessor is at or left of x.
    let right = points.partition_point(|p| p.0 <= x);
    let (x0, y0) = points[right - 1];
    let (x1, y1) = points[right];
    if x1 == x0 {
        return y1;
    }
    y0 + (y1 - y0) * (x - x0) / (x1 - x0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-12
    }

    #[test]
    fn report_mean_se_matches_hand_computation() {
        // mean 4; deviations -2, 0, 2 -> sample variance (4 + 0 + 4) / 2 = 4, sd 2, se 2/sqrt(3).
        let m = mean_se(&[2.0, 4.0, 6.0]);
        assert!(close(m.mean, 4.0));
        assert!(close(m.se, 2.0 / 3f64.sqrt()));
        assert_eq!(m.n, 3);
        // Five seeds as in the paper: 1..5 -> mean 3, sample sd sqrt(2.5), se sqrt(0.5).
        let m = mean_se(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(close(m.mean, 3.0));
        assert!(close(m.se, 0.5f64.sqrt()));
    }

    #[test]
    fn report_mean_se_of_one_and_of_none() {
        assert_eq!(
            mean_se(&[7.5]),
            MeanSe {
                mean: 7.5,
                se: 0.0,
                n: 1
            }
        );
        let none = mean_se(&[]);
        assert!(none.mean.is_nan() && none.se.is_nan());
        assert_eq!(none.n, 0);
    }

    #[test]
    fn report_linspace_includes_both_ends() {
        assert_eq!(linspace(0.0, 100.0, 5), vec![0.0, 25.0, 50.0, 75.0, 100.0]);
        assert_eq!(linspace(3.0, 9.0, 1), vec![3.0]);
        assert!(linspace(0.0, 1.0, 0).is_empty());
    }

    #[test]
    fn report_interpolate_is_linear_between_points_and_flat_outside() {
        let pts = [(0.0, 0.0), (10.0, 5.0), (30.0, 25.0)];
        assert!(close(interpolate(&pts, 0.0), 0.0));
        assert!(close(interpolate(&pts, 4.0), 2.0));
        assert!(close(interpolate(&pts, 10.0), 5.0));
        assert!(close(interpolate(&pts, 20.0), 15.0));
        assert!(close(interpolate(&pts, 30.0), 25.0));
        assert!(close(interpolate(&pts, 45.0), 25.0), "held after the end");
        assert!(close(interpolate(&pts, -3.0), 0.0), "held before the start");
        assert!(interpolate(&[], 1.0).is_nan());
    }

    #[test]
    fn report_interpolate_takes_the_later_value_at_a_repeated_x() {
        // Two episodes ending on the same step (cannot happen in one run, but the maths must not
        // divide by zero).
        let pts = [(0.0, 0.0), (10.0, 1.0), (10.0, 3.0), (20.0, 3.0)];
        assert!(close(interpolate(&pts, 10.0), 3.0));
        assert!(close(interpolate(&pts, 5.0), 0.5));
    }
}
