//! The two tail probabilities the rank tests need, from one special function: the upper
//! regularized incomplete gamma function Q(a, x) = Γ(a, x) / Γ(a).
//!
//! - chi-square with `df` degrees of freedom: P(X ≥ x) = Q(df / 2, x / 2);
//! - standard normal: P(Z ≥ z) = erfc(z / √2) / 2, and erfc(y) = Q(1/2, y²) for y ≥ 0.
//!
//! Q is evaluated as in Numerical Recipes (3rd ed., §6.2): the series for P = 1 - Q below
//! x < a + 1, Lentz's continued fraction for Q above, each to f64 rounding; ln Γ by Lanczos'
//! approximation (g = 7, nine terms), good to about 1e-15 relative. There is no statistics crate
//! in the dependency tree and these few lines are all the tests need.

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9).
pub fn ln_gamma(x: f64) -> f64 {
    debug_assert!(x > 0.0, "ln_gamma needs x > 0, got {x}");
    const G: f64 = 7.0;
    const COEFFICIENTS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut series = COEFFICIENTS[0];
    for (i, c) in COEFFICIENTS.iter().enumerate().skip(1) {
        series += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + series.ln()
}

/// The upper regularized incomplete gamma function Q(a, x) = Γ(a, x) / Γ(a), for a > 0.
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    debug_assert!(a > 0.0, "regularized_gamma_q needs a > 0, got {a}");
    if x <= 0.0 {
        return 1.0;
    }
    // x^a e^-x / Γ(a), the factor both expansions share.
    let prefactor = (a * x.ln() - x - ln_gamma(a)).exp();
    if x < a + 1.0 {
        // P(a, x) = prefactor * Σ x^n / (a (a+1) ... (a+n)).
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * f64::EPSILON {
                break;
            }
        }
        (1.0 - prefactor * sum).max(0.0)
    } else {
        // Q(a, x) = prefactor * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - 2 (2 - a) / ...)),
        // by the modified Lentz method.
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < f64::EPSILON {
                break;
            }
        }
        prefactor * h
    }
}

/// P(X ≥ x) for X chi-square distributed with `df` > 0 degrees of freedom.
pub fn chi_square_sf(x: f64, df: f64) -> f64 {
    regularized_gamma_q(df / 2.0, x / 2.0)
}

/// P(Z ≥ z) for Z standard normal.
pub fn normal_sf(z: f64) -> f64 {
    let upper = 0.5 * regularized_gamma_q(0.5, z * z / 2.0);
    if z >= 0.0 { upper } else { 1.0 - upper }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_gamma_matches_factorials_and_half_integers() {
        let mut factorial = 1.0f64;
        for n in 1..=20 {
            // Γ(n) = (n - 1)!
            assert!(
                (ln_gamma(n as f64) - factorial.ln()).abs() < 1e-12,
                "n = {n}"
            );
            factorial *= n as f64;
        }
        // Γ(1/2) = √π
        let root_pi = std::f64::consts::PI.sqrt();
        assert!((ln_gamma(0.5) - root_pi.ln()).abs() < 1e-14);
    }

    #[test]
    fn tails_match_known_quantiles() {
        // Q(1, x) = e^-x, on both sides of the switch at x = a + 1.
        for x in [0.1f64, 1.0, 1.9, 2.1, 5.0, 30.0] {
            let want = (-x).exp();
            assert!(
                (regularized_gamma_q(1.0, x) - want).abs() < 1e-13 * want,
                "x = {x}"
            );
        }
        // scipy.stats.chi2.ppf(0.95, df) for df = 1, 2, 5 and norm.ppf(0.975), norm.ppf(0.999).
        assert!((chi_square_sf(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-13);
        assert!((chi_square_sf(5.991_464_547_107_979, 2.0) - 0.05).abs() < 1e-13);
        assert!((chi_square_sf(11.070_497_693_516_351, 5.0) - 0.05).abs() < 1e-13);
        assert!((normal_sf(1.959_963_984_540_054) - 0.025).abs() < 1e-14);
        assert!((normal_sf(-1.959_963_984_540_054) - 0.975).abs() < 1e-14);
        assert!((normal_sf(3.090_232_306_167_813) - 0.001).abs() < 1e-15);
        assert_eq!(normal_sf(0.0), 0.5);
        assert_eq!(chi_square_sf(0.0, 2.0), 1.0);
    }
}
