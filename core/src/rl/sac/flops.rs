//! The arithmetic of one update, counted product by product as `update.rs` performs them.

use super::SacConfig;

/// MFLOP of the matrix products of one call of [`crate::rl::sac::Sac::update`]
/// (`gradient_steps` gradient steps): 2 x the multiply-adds of every `sgemm`. Bias, ReLU, the
/// tanh-Gaussian, Adam and Polyak are elementwise and left out.
///
/// With `F(net) = batch * sum over layers of n_in * n_out`, the multiply-adds of a forward pass:
/// a backward pass with parameter gradients costs `2 F - batch * n_0 * n_1` (no input gradient
/// at the first layer), an input-gradient-only pass (`backward_input`) costs `F`.
pub fn mflop_per_update(obs_dim: usize, act_dim: usize, config: &SacConfig) -> f64 {
    let batch = config.batch_size as f64;
    let macs = |n_in: usize, n_out: usize| {
        let (forward, first_layer) = macs_per_sample(n_in, n_out, config);
        (forward * batch, first_layer * batch)
    };
    let (actor, actor_first) = macs(obs_dim, 2 * act_dim);
    let (critic, critic_first) = macs(obs_dim + act_dim, 1);
    let backward = |forward: f64, first: f64| 2.0 * forward - first;
    let human = config.human_critic.is_some();
    let twins_in_actor_loss = if human { 4.0 } else { 2.0 };

    let step = actor // 1. actor at s
        + actor + 2.0 * critic // 3. actor at s', both target critics
        + 2.0 * (critic + backward(critic, critic_first)) // 4. critics
        + if human { 2.0 * (critic + backward(critic, critic_first)) } else { 0.0 } // 5.
        + twins_in_actor_loss * 2.0 * critic // 6. critics forward and backward_input
        + backward(actor, actor_first); // 6. actor backward
    2.0 * step * config.gradient_steps as f64 / 1e6
}

/// MFLOP of [`mflop_per_update`] that the update does not compute. The actor loss takes a
/// `min` over each twin pair per sample, so each sample's gradient reaches one head of the pair;
/// `update.rs` passes it back through that head only, and the other head's input-gradient pass
/// for that sample (an exact zero) is skipped: one critic's `backward_input` per sample and pair.
pub fn mflop_skipped_per_update(obs_dim: usize, act_dim: usize, config: &SacConfig) -> f64 {
    let (critic, _) = macs_per_sample(obs_dim + act_dim, 1, config);
    let pairs = if config.human_critic.is_some() { 2 } else { 1 };
    let samples = (pairs * config.batch_size * config.gradient_steps) as f64;
    2.0 * samples * critic / 1e6
}

/// Multiply-adds of one sample's forward pass through `n_in -> hidden -> n_out`, and of its
/// first layer alone.
fn macs_per_sample(n_in: usize, n_out: usize, config: &SacConfig) -> (f64, f64) {
    let sizes: Vec<usize> = std::iter::once(n_in)
        .chain(config.hidden.iter().copied())
        .chain(std::iter::once(n_out))
        .collect();
    let forward: f64 = sizes.windows(2).map(|p| (p[0] * p[1]) as f64).sum();
    (forward, (sizes[0] * sizes[1]) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Task;

    #[test]
    fn counts_by_hand_on_a_tiny_learner() {
        let mut config = SacConfig::for_task(Task::Reaching);
        (config.hidden, config.batch_size, config.human_critic) = (vec![2], 1, None);
        // Actor 1 -> 2 -> 2: F = 2 + 4, first layer 2. Critic 2 -> 2 -> 1: F = 4 + 2, first 4.
        // actor(s) 6, actor(s') 6, targets 12, critics 2 (6 + 8), actor loss 2 (6 + 6), actor
        // backward 10: 86 multiply-adds.
        assert_eq!(mflop_per_update(1, 1, &config), 2.0 * 86.0 / 1e6);
        // Human critics: + 2 (6 + 8) in their loss, + 2 (6 + 6) in the actor loss.
        config.human_critic = Some(Default::default());
        assert_eq!(
            mflop_per_update(1, 1, &config),
            2.0 * (86.0 + 28.0 + 24.0) / 1e6
        );
    }

    #[test]
    fn the_actor_loss_skips_one_head_per_twin_pair_and_sample() {
        let mut config = SacConfig::for_task(Task::LunarLander);
        let per_sample = 2.0 * (10.0 * 400.0 + 400.0 * 300.0 + 300.0) / 1e6;
        // Twin critics and twin human critics: two pairs.
        let skipped = mflop_skipped_per_update(8, 2, &config);
        assert!(
            (skipped - 2.0 * 512.0 * per_sample).abs() < 1e-9,
            "{skipped}"
        );
        config.human_critic = None;
        let skipped = mflop_skipped_per_update(8, 2, &config);
        assert!((skipped - 512.0 * per_sample).abs() < 1e-9, "{skipped}");
    }

    #[test]
    fn lunar_lander_update_is_3_3_gflop() {
        let config = SacConfig::for_task(Task::LunarLander);
        let mflop = mflop_per_update(8, 2, &config);
        assert!((mflop - 3290.112).abs() < 1e-6, "{mflop}");
    }
}
