//! `answer_replay`: the human critic regresses a batch of its own, drawn from the answered
//! transitions, while SAC's batch and noise are drawn exactly as without it.

use super::tiny_config;
use crate::rl::replay::{ReplayBuffer, Transition};
use crate::rl::sac::{HumanCriticConfig, Sac};

/// 200 transitions, observation `[k / 200, 1, -1]`; H = +1 on the slots in `answered`.
fn replay(answered: &[usize]) -> ReplayBuffer {
    let mut replay = ReplayBuffer::new(256, 3, 2);
    for k in 0..200 {
        let obs = [k as f32 / 200.0, 1.0, -1.0];
        replay.push(Transition {
            obs: &obs,
            action: &[0.3, -0.3],
            reward: 0.1,
            human: if answered.contains(&k) { 1.0 } else { 0.0 },
            next_obs: &obs,
            terminated: false,
        });
    }
    replay
}

fn learner(answer_replay: bool) -> Sac {
    let human = HumanCriticConfig {
        mask: true,
        answer_replay,
        ..HumanCriticConfig::default()
    };
    Sac::new(3, 2, tiny_config(&[6, 5], 16, Some(human)), 11)
}

#[test]
fn the_critic_steps_on_answers_that_sacs_batch_missed() {
    // One answered transition in 200: a batch of 16 rarely holds it.
    let replay = replay(&[37]);
    let (mut own, mut shared) = (learner(true), learner(false));
    let (mut own_steps, mut shared_steps) = (0, 0);
    for update in 0..20 {
        let own_stats = own.update(&replay).unwrap();
        let shared_stats = shared.update(&replay).unwrap();
        if update == 0 {
            // SAC's batch is drawn first, from the same generator: the same rows in both (the
            // answers' draws come after, so later batches part).
            assert_eq!(own.buffers.batch.obs, shared.buffers.batch.obs);
        }
        let answers = own.buffers.answer_batch.as_ref().unwrap();
        assert!(answers.human.iter().all(|&h| h == 1.0));
        assert!(answers.obs.chunks(3).all(|o| o[0] == 37.0 / 200.0));
        own_steps += usize::from(own_stats.human_critic_loss > 0.0);
        shared_steps += usize::from(shared_stats.human_critic_loss > 0.0);
    }
    assert_eq!(own_steps, 20, "a step on the answer at every update");
    assert!(
        shared_steps < 10,
        "the shared batch held it {shared_steps} times of 20"
    );
}

#[test]
fn no_answers_no_step() {
    let replay = replay(&[]);
    let mut sac = learner(true);
    let before = sac.human_critic.as_ref().unwrap().h1.clone();
    let stats = sac.update(&replay).unwrap();
    assert_eq!(stats.human_critic_loss, 0.0);
    assert_eq!(sac.human_critic.as_ref().unwrap().h1, before);
}
