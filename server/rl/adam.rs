//! Adam (Kingma & Ba 2015) as `torch.optim.Adam` computes it on the CPU.

/// Adam's hyper-parameters; the defaults are PyTorch's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamConfig {
    /// Learning rate (PyTorch: 1e-3; SAC's per-task values are in `algorithms.md`).
    pub lr: f64,
    /// Decay of the first-moment estimate.
    pub beta1: f64,
    /// Decay of the second-moment estimate.
    pub beta2: f64,
    /// Added to the bias-corrected `sqrt(v)` in the denominator.
    pub eps: f64,
}

impl Default for AdamConfig {
    fn default() -> Self {
        Self {
            lr: 1e-3,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }
}

impl AdamConfig {
    pub fn with_lr(lr: f64) -> Self {
        Self {
            lr,
            ..Self::default()
        }
    }
}

/// Adam over a fixed set of parameter groups (flat slices, e.g. one per network: a twin critic
/// is two groups under one optimiser, as SB3's critic optimiser covers `q1` and `q2`).
///
/// Owns the moment estimates, allocated once in [`Adam::new`]; [`Adam::step`] allocates nothing.
/// Gradients belong to the networks, so zeroing them is [`crate::rl::Mlp::zero_grad`].
#[derive(Clone, Debug)]
pub struct Adam {
    pub config: AdamConfig,
    /// Steps taken so far (PyTorch's `state["step"]`, shared by all groups here since every
    /// group is updated at every step).
    t: u64,
    /// First-moment estimate per group.
    m: Vec<Vec<f32>>,
    /// Second-moment estimate per group.
    v: Vec<Vec<f32>>,
}

impl Adam {
    /// An optimiser for groups of the given lengths (e.g. `&[q1.params().len(), q2.params().len()]`).
    pub fn new(config: AdamConfig, group_lens: &[usize]) -> Self {
        Self {
            config,
            t: 0,
            m: group_lens.iter().map(|&n| vec![0.0; n]).collect(),
            v: group_lens.iter().map(|&n| vec![0.0; n]).collect(),
        }
    }

    pub fn steps(&self) -> u64 {
        self.t
    }

    /// Each group's first- and second-moment estimates (PyTorch's `exp_avg`, `exp_avg_sq`),
    /// for checkpoints.
    pub fn moments(&self) -> impl Iterator<Item = (&[f32], &[f32])> {
        self.m.iter().zip(&self.v).map(|(m, v)| (&m[..], &v[..]))
    }

    /// Restore a checkpointed state: the step count, then each group's moments in place.
    pub fn moments_mut(&mut self, steps: u64) -> impl Iterator<Item = (&mut [f32], &mut [f32])> {
        self.t = steps;
        self.m
            .iter_mut()
            .zip(&mut self.v)
            .map(|(m, v)| (&mut m[..], &mut v[..]))
    }

    /// One update of every group, given as `(params, grads)` pairs in the order of
    /// [`Adam::new`] (e.g. `adam.step([q1.params_and_grads(), q2.params_and_grads()])`).
    ///
    /// Follows `torch.optim.adam._single_tensor_adam` operation by operation, so results agree
    /// with PyTorch to f32 rounding:
    ///
    /// ```text
    /// m = lerp(m, g, 1 - beta1)                 // = beta1 m + (1 - beta1) g
    /// v = beta2 v + (1 - beta2) g^2
    /// p -= lr / (1 - beta1^t) * m / (sqrt(v) / sqrt(1 - beta2^t) + eps)
    /// ```
    pub fn step<'a>(&mut self, groups: impl IntoIterator<Item = (&'a mut [f32], &'a [f32])>) {
        self.t += 1;
        let c = self.config;
        // Scalars in f64 as Python computes them, then rounded once to the tensors' f32.
        let t = self.t as f64;
        let step_size = (c.lr / (1.0 - c.beta1.powf(t))) as f32;
        let bias_correction2_sqrt = (1.0 - c.beta2.powf(t)).sqrt() as f32;
        let (one_minus_beta1, beta2, one_minus_beta2, eps) = (
            (1.0 - c.beta1) as f32,
            c.beta2 as f32,
            (1.0 - c.beta2) as f32,
            c.eps as f32,
        );

        let mut count = 0;
        for ((params, grads), (m, v)) in groups.into_iter().zip(self.m.iter_mut().zip(&mut self.v))
        {
            count += 1;
            assert!(
                params.len() == m.len() && grads.len() == m.len(),
                "Adam group {count}: {} params and {} grads for a group of {}",
                params.len(),
                grads.len(),
                m.len()
            );
            for (((p, &g), m), v) in params
                .iter_mut()
                .zip(grads)
                .zip(m.iter_mut())
                .zip(v.iter_mut())
            {
                // torch.lerp with weight < 0.5 is `start + weight * (end - start)`.
                *m += one_minus_beta1 * (g - *m);
                *v = *v * beta2 + one_minus_beta2 * g * g;
                let denom = v.sqrt() / bias_correction2_sqrt + eps;
                *p += -step_size * (*m / denom);
            }
        }
        assert_eq!(
            count,
            self.m.len(),
            "Adam::step got {count} groups, expected {}",
            self.m.len()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_moves_each_parameter_by_lr_against_its_gradient_sign() {
        // After one step m / sqrt(v) is g / |g| once bias-corrected, so |delta| = lr (up to eps).
        let mut adam = Adam::new(AdamConfig::with_lr(0.01), &[3, 1]);
        let (mut a, mut b) = ([1.0f32, 1.0, 1.0], [5.0f32]);
        adam.step([
            (&mut a[..], &[2.0f32, -1e-3, 0.0][..]),
            (&mut b[..], &[-40.0f32][..]),
        ]);
        assert!((a[0] - 0.99).abs() < 1e-6, "{a:?}");
        assert!((a[1] - 1.01).abs() < 1e-6, "{a:?}");
        assert_eq!(a[2], 1.0, "zero gradient, no move");
        assert!((b[0] - 5.01).abs() < 1e-6, "{b:?}");
        assert_eq!(adam.steps(), 1);
    }

    #[test]
    #[should_panic(expected = "expected 2")]
    fn a_missing_group_is_an_error() {
        let mut adam = Adam::new(AdamConfig::default(), &[1, 1]);
        let mut p = [0.0f32];
        adam.step([(&mut p[..], &[1.0f32][..])]);
    }
}
