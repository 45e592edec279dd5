//! Tests that need the learner's insides: a fixed batch and fixed noise injected into its step
//! buffers, and each loss on its own.

mod answer_replay;
mod gradients;
mod refit;
mod target;
mod threads;
mod torch_reference;

use super::{CriticLoss, HumanCriticConfig, Sac, SacConfig};

/// Tiny hyper-parameters for tests: `hidden`, batch `batch`, the rest SB3-like.
fn tiny_config(hidden: &[usize], batch: usize, human: Option<HumanCriticConfig>) -> SacConfig {
    SacConfig {
        hidden: hidden.to_vec(),
        learning_rate: 0.01,
        batch_size: batch,
        buffer_size: 100,
        tau: 0.05,
        gamma: 0.99,
        learning_starts: 0,
        gradient_steps: 1,
        init_ent_coef: 0.5,
        target_entropy: Some(-2.0),
        human_critic: human,
        critic_loss: CriticLoss::Mse,
        critic_layer_norm: false,
    }
}

/// `f(k)` for `k = 0..values.len()`, computed in f64 and rounded to f32 (as the PyTorch
/// reference scripts do).
fn fill(values: &mut [f32], f: impl Fn(f64) -> f64) {
    for (k, v) in values.iter_mut().enumerate() {
        *v = f(k as f64) as f32;
    }
}

/// The batch and noise of `benches/reference/torch_sac_reference.py` (any batch size: the
/// feedback and termination patterns repeat every 5 rows).
fn fill_fixed_batch_and_noise(sac: &mut Sac) {
    let b = &mut sac.buffers;
    fill(&mut b.batch.obs, |k| (0.5 * k).cos());
    fill(&mut b.batch.next_obs, |k| (0.5 * k + 0.3).cos());
    fill(&mut b.batch.actions, |k| 0.9 * (0.7 * k + 0.2).sin());
    fill(&mut b.noise_pi, |k| 1.2 * (0.9 * k + 0.4).sin());
    fill(&mut b.noise_next, |k| (0.8 * k + 0.1).cos());
    fill(&mut b.batch.rewards, |i| (1.1 * i + 0.5).sin());
    fill(&mut b.batch.human, |i| {
        [1.0, 0.0, -1.0, 0.0, 1.0][i as usize % 5]
    });
    fill(&mut b.batch.dones, |i| {
        [0.0, 1.0, 0.0, 0.0, 0.0][i as usize % 5]
    });
}
