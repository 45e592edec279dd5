//! Losses with their gradients, written into a workspace's output-gradient buffer.

/// Mean squared error `L = mean((prediction - target)^2)` over all elements (PyTorch's
/// `F.mse_loss` with `reduction = "mean"`), returning `L` and overwriting `grad` with
/// `dL/d prediction = 2 (prediction - target) / n`.
///
/// The sum is accumulated in f64 so the reported loss does not depend on the batch order.
/// Scale `grad` afterwards for a weighted loss (SB3's critic loss is `0.5 * sum_j mse(q_j, y)`).
pub fn mse_loss(prediction: &[f32], target: &[f32], grad: &mut [f32]) -> f32 {
    check_lengths("mse_loss", prediction, target, grad);
    let n = target.len() as f32;
    let mut sum = 0.0f64;
    for ((g, &p), &y) in grad.iter_mut().zip(prediction).zip(target) {
        let diff = p - y;
        sum += f64::from(diff) * f64::from(diff);
        *g = 2.0 * diff / n;
    }
    (sum / target.len() as f64) as f32
}

/// One prediction and one gradient slot per target, and at least one target.
fn check_lengths(loss: &str, prediction: &[f32], target: &[f32], grad: &[f32]) {
    assert!(
        prediction.len() == target.len() && grad.len() == target.len() && !target.is_empty(),
        "{loss}: {} predictions, {} targets, {} gradient slots",
        prediction.len(),
        target.len(),
        grad.len()
    );
}

/// Huber loss `L = mean(h(prediction - target))`, `h(d) = 0.5 d^2` where `|d| <= 1` and
/// `|d| - 0.5` beyond (PyTorch's `F.huber_loss` at its default `delta = 1`, which is
/// `F.smooth_l1_loss` at `beta = 1`, the loss stable-baselines3's DQN fits its Q with), returning
/// `L` and overwriting `grad` with `dL/d prediction = clamp(d, -1, 1) / n`.
///
/// Beside [`mse_loss`] it bounds what one sample can pull: a target an outlier away (a crash's
/// -100 on Lunar Lander, or a target network that ran ahead) moves the critic as much as any
/// other sample that is off by more than 1, not in proportion to how far off it is.
pub fn huber_loss(prediction: &[f32], target: &[f32], grad: &mut [f32]) -> f32 {
    check_lengths("huber_loss", prediction, target, grad);
    let n = target.len() as f32;
    let mut sum = 0.0f64;
    for ((g, &p), &y) in grad.iter_mut().zip(prediction).zip(target) {
        let diff = p - y;
        let value = if diff.abs() <= 1.0 {
            0.5 * f64::from(diff) * f64::from(diff)
        } else {
            f64::from(diff.abs()) - 0.5
        };
        sum += value;
        *g = diff.clamp(-1.0, 1.0) / n;
    }
    (sum / target.len() as f64) as f32
}

/// `mse` over the answered rows (`target != 0`) plus `anchor` times the mean of `prediction^2`
/// over the others: each group is a mean of its own, so answers keep their weight however few
/// they are. With `anchor = 0` the unanswered rows get no gradient (the plain mask). A group
/// with no rows adds nothing; the caller ensures the loss has at least one row.
pub fn anchored_mse_loss(prediction: &[f32], target: &[f32], anchor: f32, grad: &mut [f32]) -> f32 {
    let answered = target.iter().filter(|&&y| y != 0.0).count();
    let silent = target.len() - answered;
    let (mut answered_sum, mut silent_sum) = (0.0f64, 0.0f64);
    for ((g, &p), &y) in grad.iter_mut().zip(prediction).zip(target) {
        if y != 0.0 {
            let diff = p - y;
            answered_sum += f64::from(diff) * f64::from(diff);
            *g = 2.0 * diff / answered as f32;
        } else if anchor > 0.0 {
            silent_sum += f64::from(p) * f64::from(p);
            *g = anchor * 2.0 * p / silent as f32;
        } else {
            *g = 0.0;
        }
    }
    let mean = |sum: f64, n: usize| if n == 0 { 0.0 } else { sum / n as f64 };
    (mean(answered_sum, answered) + f64::from(anchor) * mean(silent_sum, silent)) as f32
}

/// Which loss a critic regresses its targets with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Regression {
    /// [`mse_loss`].
    Mse,
    /// [`huber_loss`].
    Huber,
    /// [`anchored_mse_loss`] with this anchor (0: the plain mask).
    AnchoredMse(f32),
}

impl Regression {
    /// The loss of `prediction` against `target`, its gradient written into `grad`.
    pub fn loss(self, prediction: &[f32], target: &[f32], grad: &mut [f32]) -> f32 {
        match self {
            Self::Mse => mse_loss(prediction, target, grad),
            Self::Huber => huber_loss(prediction, target, grad),
            Self::AnchoredMse(anchor) => anchored_mse_loss(prediction, target, anchor, grad),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mse_and_its_gradient_by_hand() {
        let mut grad = [9.0f32; 2];
        let loss = mse_loss(&[1.0, -1.0], &[0.0, 1.0], &mut grad);
        assert_eq!(loss, 2.5); // (1 + 4) / 2
        assert_eq!(grad, [1.0, -2.0]); // 2 * (1, -2) / 2
    }

    #[test]
    fn huber_and_its_gradient_by_hand() {
        // Differences 0.5 (quadratic), -3 (linear), 1 (the seam, both branches agree).
        let mut grad = [9.0f32; 3];
        let loss = huber_loss(&[1.5, -1.0, 2.0], &[1.0, 2.0, 1.0], &mut grad);
        assert_eq!(loss, (0.125 + 2.5 + 0.5) / 3.0);
        assert_eq!(grad, [0.5 / 3.0, -1.0 / 3.0, 1.0 / 3.0]);
    }

    #[test]
    fn huber_is_half_the_mse_near_the_target() {
        let (prediction, target) = ([0.1f32, -0.4, 0.9], [0.0f32, 0.2, 0.3]);
        let (mut g_huber, mut g_mse) = ([0.0f32; 3], [0.0f32; 3]);
        let huber = huber_loss(&prediction, &target, &mut g_huber);
        let mse = mse_loss(&prediction, &target, &mut g_mse);
        assert!((huber - 0.5 * mse).abs() < 1e-7);
        for (h, m) in g_huber.iter().zip(&g_mse) {
            assert!((h - 0.5 * m).abs() < 1e-7);
        }
    }
}
