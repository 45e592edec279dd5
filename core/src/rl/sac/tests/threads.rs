//! Two threads run the twin critics side by side (`kernels::side_by_side`); one thread runs
//! them one after the other. Every network, optimiser state and loss must come out the same
//! bits either way, on every kernel path, for each actor loss.

use super::super::config::ActorMix;
use super::{HumanCriticConfig, Sac, fill_fixed_batch_and_noise, tiny_config};
use crate::rl::kernels;

/// Five gradient steps on the fixed batch: the learner's checksum (networks, targets,
/// optimisers, temperature) and every loss, as bits.
fn steps_on(threads: usize, human: Option<HumanCriticConfig>) -> (u64, Vec<u32>) {
    kernels::with_threads(threads, || {
        // Wide enough that the picked heads differ between samples and the products are tiled.
        let mut sac = Sac::new(3, 2, tiny_config(&[40, 24], 37, human), 5);
        let mut losses = Vec::new();
        for _ in 0..5 {
            fill_fixed_batch_and_noise(&mut sac);
            let s = sac.gradient_step();
            losses.extend(
                [s.critic_loss, s.actor_loss, s.human_critic_loss, s.ent_coef].map(f32::to_bits),
            );
        }
        (sac.state_checksum(), losses)
    })
}

#[test]
fn twin_critics_side_by_side_give_the_bits_of_one_thread() {
    let humans = [
        None,
        Some(HumanCriticConfig::default()),
        Some(HumanCriticConfig {
            mix: ActorMix::Paper,
            mask: true,
            ..HumanCriticConfig::default()
        }),
    ];
    kernels::on_every_path(|path| {
        for human in &humans {
            let one = steps_on(1, human.clone());
            let two = steps_on(2, human.clone());
            assert_eq!(one, two, "{path}, human critic {human:?}");
        }
    });
}
