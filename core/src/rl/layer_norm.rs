//! Layer normalisation of one hidden layer's pre-activations (PyTorch's `nn.LayerNorm(n)` with
//! its defaults: `eps = 1e-5`, a gain and a bias per feature, initialised to 1 and 0), its
//! forward pass fused with the ReLU after it, and its backward pass.
//!
//! Why a critic gets it: on Lunar Lander the runs that end lowest are those whose env critic values
//! the policy far above anything it earns (docs/dref-lunar-lander.md, "What decides a Lunar Lander
//! run"). Normalised, each hidden layer's features have norm `sqrt(n)` times the gain, whatever the
//! input, so a critic cannot extrapolate to ever larger values on inputs unlike its data unless its
//! last layer's weights grow; this is the critic of Ball et al. 2023 (RLPD) and Nauman et al. 2024,
//! who report it curbs exactly that overestimation in SAC.
//!
//! Every column (sample) is normalised on its own, over the layer's `n` features, in scalar code
//! with a fixed order: the same bits on every kernel path for the same pre-activations, and the
//! same bits for a column whatever the batch around it.

use std::ops::Range;

/// PyTorch's `nn.LayerNorm` default.
pub const EPS: f32 = 1e-5;

/// Where one layer norm's gain and bias sit in a network's flat parameter vector: `n` gains,
/// then `n` biases (PyTorch's `weight`, `bias`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LayerNorm {
    pub n: usize,
    /// Index of the first gain in the flat parameter (and gradient) vector.
    pub offset: usize,
}

impl LayerNorm {
    pub fn gain_range(&self) -> Range<usize> {
        self.offset..self.offset + self.n
    }

    pub fn bias_range(&self) -> Range<usize> {
        self.offset + self.n..self.offset + 2 * self.n
    }
}

/// What the backward pass needs of one layer norm's forward pass at one batch size.
#[derive(Clone, Debug, PartialEq)]
pub struct NormCache {
    /// `(z - mean) / sqrt(var + eps)`, column-major `n x batch`.
    pub normalized: Vec<f32>,
    /// `1 / sqrt(var + eps)` per column.
    pub inv_std: Vec<f32>,
}

impl NormCache {
    pub fn new(n: usize, batch: usize) -> Self {
        Self {
            normalized: vec![0.0; n * batch],
            inv_std: vec![0.0; batch],
        }
    }
}

/// In place over the first `batch` columns of `z` (`n x batch`, column-major): `z` becomes
/// `relu(gain * normalised(z) + bias)`; `cache` keeps the normalised values and `1 / std`.
/// The variance is the biased one, as PyTorch's.
pub fn forward_relu(norm: &LayerNorm, params: &[f32], z: &mut [f32], cache: &mut NormCache) {
    let n = norm.n;
    let (gain, bias) = (&params[norm.gain_range()], &params[norm.bias_range()]);
    let columns = z
        .chunks_exact_mut(n)
        .zip(cache.normalized.chunks_exact_mut(n))
        .zip(cache.inv_std.iter_mut());
    for ((column, normalized), inv_std) in columns {
        let mean = column.iter().sum::<f32>() / n as f32;
        let var = column.iter().map(|&v| (v - mean) * (v - mean)).sum::<f32>() / n as f32;
        let inv = 1.0 / (var + EPS).sqrt();
        *inv_std = inv;
        for (((v, x_hat), &g), &b) in column.iter_mut().zip(normalized).zip(gain).zip(bias) {
            *x_hat = (*v - mean) * inv;
            *v = (g * *x_hat + b).max(0.0);
        }
    }
}

/// In place over the first `batch` columns of `dy` (dL/d of the norm's output, already through
/// the ReLU after it): `dy` becomes dL/dz, the gradient at the norm's input. With `param_grads`
/// (the network's flat gradient vector), adds dL/d gain and dL/d bias there.
///
/// `dz = inv_std * (d_hat - mean(d_hat) - x_hat * mean(d_hat * x_hat))`, `d_hat = gain * dy`.
pub fn backward(
    norm: &LayerNorm,
    params: &[f32],
    param_grads: Option<&mut [f32]>,
    dy: &mut [f32],
    cache: &NormCache,
    batch: usize,
) {
    let n = norm.n;
    let dy = &mut dy[..n * batch];
    let normalized = &cache.normalized[..n * batch];
    if let Some(grads) = param_grads {
        let (gain_grad, bias_grad) = grads[norm.offset..norm.offset + 2 * n].split_at_mut(n);
        for (dy, x_hat) in dy.chunks_exact(n).zip(normalized.chunks_exact(n)) {
            for (((dg, db), &d), &x) in gain_grad
                .iter_mut()
                .zip(bias_grad.iter_mut())
                .zip(dy)
                .zip(x_hat)
            {
                *dg += d * x;
                *db += d;
            }
        }
    }
    let gain = &params[norm.gain_range()];
    let columns = dy
        .chunks_exact_mut(n)
        .zip(normalized.chunks_exact(n))
        .zip(&cache.inv_std[..batch]);
    for ((dy, x_hat), &inv) in columns {
        let mut sum = 0.0f32;
        let mut sum_x = 0.0f32;
        for ((d, &g), &x) in dy.iter_mut().zip(gain).zip(x_hat) {
            *d *= g;
            sum += *d;
            sum_x += *d * x;
        }
        let (mean, mean_x) = (sum / n as f32, sum_x / n as f32);
        for (d, &x) in dy.iter_mut().zip(x_hat) {
            *d = inv * (*d - mean - x * mean_x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_is_normalised_to_zero_mean_and_unit_variance_before_gain_and_bias() {
        let norm = LayerNorm { n: 4, offset: 0 };
        let params = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0];
        let mut z = [1.0, 2.0, 3.0, 6.0, -1.0, -1.0, -1.0, -1.0];
        let mut cache = NormCache::new(4, 2);
        forward_relu(&norm, &params, &mut z, &mut cache);
        let x_hat = &cache.normalized[..4];
        let mean: f32 = x_hat.iter().sum::<f32>() / 4.0;
        let var: f32 = x_hat.iter().map(|x| x * x).sum::<f32>() / 4.0;
        assert!(mean.abs() < 1e-6 && (var - 1.0).abs() < 1e-4, "{x_hat:?}");
        // A constant column has no spread: all zeros, with 1/std = 1/sqrt(eps).
        assert_eq!(&cache.normalized[4..], &[0.0; 4]);
        assert!((cache.inv_std[1] - 1.0 / EPS.sqrt()).abs() < 1.0);
        // The ReLU after it.
        for (&v, &x) in z[..4].iter().zip(x_hat) {
            assert_eq!(v, x.max(0.0));
        }
    }
}
