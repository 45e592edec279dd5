//! SAC's policy distribution: a diagonal Gaussian squashed by tanh, with the log-probability
//! corrected for the squashing (Haarnoja et al. 2018, appendix C), and its hand-written gradient.
//!
//! Per sample the actor's head gives `[mu; log_std]` (2 x dim(A) values). With noise
//! `eps ~ N(0, I)`: `u = mu + exp(log_std) * eps`, `a = tanh(u)`, and
//! `log pi(a|s) = sum_k [ -eps_k^2 / 2 - log_std_k - ln(2 pi) / 2 - ln(1 - a_k^2 + 1e-6) ]`.
//! `log_std` is clamped to [-20, 2] first (SB3), and the 1e-6 keeps the log finite at |a| = 1,
//! as in SB3 and CleanRL.

/// Bounds on the log standard deviation (SB3's `LOG_STD_MIN`, `LOG_STD_MAX`).
pub const LOG_STD_MIN: f32 = -20.0;
pub const LOG_STD_MAX: f32 = 2.0;
/// Keeps `ln(1 - tanh(u)^2)` finite when tanh saturates.
const SQUASH_EPS: f32 = 1e-6;
const HALF_LN_2PI: f32 = 0.918_938_5;

/// Sample one action. `head` = `[mu; log_std]`, `eps` = standard normal noise (dim(A) values);
/// writes the action into `action` and returns `log pi(action | s)`.
pub fn sample(head: &[f32], eps: &[f32], action: &mut [f32]) -> f32 {
    let dim = action.len();
    debug_assert_eq!(head.len(), 2 * dim);
    let mut log_prob = 0.0;
    for k in 0..dim {
        let log_std = head[dim + k].clamp(LOG_STD_MIN, LOG_STD_MAX);
        let a = (head[k] + log_std.exp() * eps[k]).tanh();
        action[k] = a;
        log_prob +=
            -0.5 * eps[k] * eps[k] - log_std - HALF_LN_2PI - (1.0 - a * a + SQUASH_EPS).ln();
    }
    log_prob
}

/// The deterministic action of evaluation: `tanh(mu)`.
pub fn mean_action(head: &[f32], action: &mut [f32]) {
    for (a, mu) in action.iter_mut().zip(head) {
        *a = mu.tanh();
    }
}

/// Back-propagate through [`sample`] with the same `head`, `eps` and resulting `action`, for a
/// loss `L(action, log_prob)` with partial derivatives `dl_da` (w.r.t. the action, dim(A)
/// values) and `dl_dlogp`. Writes `dL/d[mu; log_std]` into `dl_dhead`.
pub fn backward(
    head: &[f32],
    eps: &[f32],
    action: &[f32],
    dl_da: &[f32],
    dl_dlogp: f32,
    dl_dhead: &mut [f32],
) {
    let dim = action.len();
    for k in 0..dim {
        let a = action[k];
        let raw_log_std = head[dim + k];
        let std = raw_log_std.clamp(LOG_STD_MIN, LOG_STD_MAX).exp();
        // log pi depends on a through -ln(1 - a^2 + eps): d/da = 2a / (1 - a^2 + eps).
        let dl_da_total = dl_da[k] + dl_dlogp * 2.0 * a / (1.0 - a * a + SQUASH_EPS);
        let dl_du = dl_da_total * (1.0 - a * a);
        dl_dhead[k] = dl_du;
        // u = mu + std * eps, and log pi has -log_std (the Gaussian's (u - mu)/std = eps is
        // constant under the reparameterisation). The clamp passes no gradient outside its range.
        let inside = (LOG_STD_MIN..=LOG_STD_MAX).contains(&raw_log_std);
        dl_dhead[dim + k] = if inside {
            dl_du * std * eps[k] - dl_dlogp
        } else {
            0.0
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A loss that uses both outputs: L = sum_k w_k a_k + c log pi.
    fn loss(head: &[f32], eps: &[f32], w: &[f32], c: f32) -> f64 {
        let mut a = vec![0.0; eps.len()];
        let logp = sample(head, eps, &mut a);
        a.iter().zip(w).map(|(a, w)| f64::from(a * w)).sum::<f64>() + f64::from(c * logp)
    }

    #[test]
    fn log_prob_matches_the_change_of_variables_formula() {
        // One dimension: density of a = tanh(u), u ~ N(mu, std^2) is N(u) / (1 - a^2).
        let (mu, log_std, eps) = (0.3f32, -0.5f32, 0.7f32);
        let mut a = [0.0];
        let logp = sample(&[mu, log_std], &[eps], &mut a);
        let std = log_std.exp() as f64;
        let u = mu as f64 + std * eps as f64;
        let normal = (-0.5 * ((u - mu as f64) / std).powi(2)).exp()
            / (std * (2.0 * std::f64::consts::PI).sqrt());
        let expected = (normal / (1.0 - u.tanh().powi(2))).ln();
        assert!(
            (f64::from(logp) - expected).abs() < 1e-4,
            "{logp} vs {expected}"
        );
        assert!((f64::from(a[0]) - u.tanh()).abs() < 1e-6);
    }

    #[test]
    fn gradient_matches_central_differences() {
        let head = [0.2f32, -0.7, -0.3, 0.4];
        let eps = [0.9f32, -1.3];
        let (w, c) = ([0.6f32, -1.1], 0.35f32);
        let mut a = [0.0; 2];
        sample(&head, &eps, &mut a);
        let mut grad = [0.0; 4];
        backward(&head, &eps, &a, &w, c, &mut grad);
        for i in 0..4 {
            let h = 1e-3;
            let mut plus = head;
            plus[i] += h;
            let mut minus = head;
            minus[i] -= h;
            let numeric =
                (loss(&plus, &eps, &w, c) - loss(&minus, &eps, &w, c)) / (2.0 * f64::from(h));
            let rel = (f64::from(grad[i]) - numeric).abs() / numeric.abs().max(1e-3);
            assert!(
                rel < 1e-2,
                "d/dhead[{i}]: analytic {} numeric {numeric}",
                grad[i]
            );
        }
    }

    #[test]
    fn clamped_log_std_passes_no_gradient() {
        let head = [0.0f32, 5.0];
        let mut a = [0.0];
        sample(&head, &[0.5], &mut a);
        let mut grad = [0.0; 2];
        backward(&head, &[0.5], &a, &[1.0], 1.0, &mut grad);
        assert_eq!(grad[1], 0.0);
        assert!(
            a[0] > (2.0f32.exp() * 0.5).tanh() - 1e-6,
            "log_std clamped to 2 in the sample"
        );
    }

    #[test]
    fn mean_action_is_tanh_of_mu() {
        let mut a = [0.0; 2];
        mean_action(&[0.5, -2.0, 9.0, 9.0], &mut a);
        assert_eq!(a, [0.5f32.tanh(), (-2.0f32).tanh()]);
    }
}
