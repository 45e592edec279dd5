//! Losses with their gradients, written into a workspace's output-gradient buffer.

/// Mean squared error `L = mean((prediction - target)^2)` over all elements (PyTorch's
/// `F.mse_loss` with `reduction = "mean"`), returning `L` and overwriting `grad` with
/// `dL/d prediction = 2 (prediction - target) / n`.
///
/// The sum is accumulated in f64 so the reported loss does not depend on the batch order.
/// Scale `grad` afterwards for a weighted loss (SB3's critic loss is `0.5 * sum_j mse(q_j, y)`).
pub fn mse_loss(prediction: &[f32], target: &[f32], grad: &mut [f32]) -> f32 {
    assert!(
        prediction.len() == target.len() && grad.len() == target.len() && !target.is_empty(),
        "mse_loss: {} predictions, {} targets, {} gradient slots",
        prediction.len(),
        target.len(),
        grad.len()
    );
    let n = target.len() as f32;
    let mut sum = 0.0f64;
    for ((g, &p), &y) in grad.iter_mut().zip(prediction).zip(target) {
        let diff = p - y;
        sum += f64::from(diff) * f64::from(diff);
        *g = 2.0 * diff / n;
    }
    (sum / target.len() as f64) as f32
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
}
