//! `dualrep_core::rl::sac` through its public API: configuration overrides, checkpoints, and that
//! it learns.

use dualrep_core::rl::replay::{ReplayBuffer, Transition};
use dualrep_core::rl::sac::{ActorMix, HumanCriticConfig, Sac, SacConfig};
use dualrep_core::sim::Task;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn small_config(human: bool) -> SacConfig {
    let mut config = SacConfig::for_task(Task::Reaching);
    config.hidden = vec![32, 32];
    config.batch_size = 64;
    config.learning_rate = 3e-3;
    config.human_critic = human.then(HumanCriticConfig::default);
    config
}

// --- configuration -------------------------------------------------------------------------

#[test]
fn per_task_table() {
    let ll = SacConfig::for_task(Task::LunarLander);
    assert_eq!(
        (ll.hidden.clone(), ll.learning_rate),
        (vec![400, 300], 7.3e-4)
    );
    assert_eq!(SacConfig::for_task(Task::Reaching).hidden, [64, 64]);
    assert_eq!(SacConfig::for_task(Task::Placing).hidden, [128, 128]);
    for task in Task::ALL {
        let c = SacConfig::for_task(task);
        assert_eq!(
            (
                c.batch_size,
                c.buffer_size,
                c.learning_starts,
                c.gradient_steps
            ),
            (512, 1_000_000, 0, 1)
        );
        assert_eq!(
            (c.tau, c.gamma, c.init_ent_coef, c.target_entropy),
            (0.01, 0.99, 1.0, None)
        );
        assert_eq!(
            c.human_critic,
            Some(HumanCriticConfig {
                lambda: 9.0,
                mix: ActorMix::Authors,
                mask: false,
                anchor: 0.0,
                unanswered: 0.0,
                answered_after: 0,
                agree_within: 0.0,
                failure_window: 0,
                authors_until: 0,
                authors_fade: 0,
                unread_to_q: false,
                answer_replay: false,
            })
        );
    }
}

fn random_replay(obs_dim: usize, act_dim: usize, n: usize, seed: u64) -> ReplayBuffer {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut replay = ReplayBuffer::new(n, obs_dim, act_dim);
    for _ in 0..n {
        let mut v = |d: usize| {
            (0..d)
                .map(|_| rng.random_range(-1.0..1.0))
                .collect::<Vec<f32>>()
        };
        let (obs, action, next_obs) = (v(obs_dim), v(act_dim), v(obs_dim));
        replay.push(Transition {
            obs: &obs,
            action: &action,
            reward: obs[0] - action[0],
            human: [-1.0, 0.0, 0.0, 1.0][(obs[1].abs() * 4.0) as usize % 4],
            next_obs: &next_obs,
            terminated: obs[2] > 0.8,
        });
    }
    replay
}

/// Same tensors (names, shapes, bytes) and the same metadata. (The header's JSON map order is
/// not fixed, so the files themselves may differ.)
fn assert_same_checkpoint(a: &[u8], b: &[u8]) {
    use safetensors::SafeTensors;
    let metadata = |bytes| {
        SafeTensors::read_metadata(bytes)
            .unwrap()
            .1
            .metadata()
            .clone()
    };
    assert_eq!(metadata(a), metadata(b));
    let (a, b) = (
        SafeTensors::deserialize(a).unwrap(),
        SafeTensors::deserialize(b).unwrap(),
    );
    let (mut names_a, mut names_b) = (a.names(), b.names());
    names_a.sort();
    names_b.sort();
    assert_eq!(names_a, names_b);
    for name in names_a {
        let (ta, tb) = (a.tensor(name).unwrap(), b.tensor(name).unwrap());
        assert_eq!(ta.shape(), tb.shape(), "{name}");
        assert!(ta.data() == tb.data(), "tensor {name} differs");
    }
}

/// A small learner with a human critic, its env critics layer-normed if `critic_layer_norm`.
fn resumable_config(critic_layer_norm: bool) -> SacConfig {
    let mut config = small_config(true);
    config.hidden = vec![16, 8];
    config.batch_size = 32;
    config.critic_layer_norm = critic_layer_norm;
    config
}

/// Five updates, a checkpoint, seven more from it and straight on: the same bytes. Returns the
/// learner that never stopped, and the checkpoint.
fn resume_is_bit_identical(config: SacConfig) -> (Sac, Vec<u8>) {
    let replay = random_replay(5, 2, 300, 1);
    let mut straight = Sac::new(5, 2, config.clone(), 7);
    let mut resumed = Sac::new(5, 2, config, 7);
    let mut action = [0.0f32; 2];
    for _ in 0..5 {
        straight.update(&replay).unwrap();
        resumed.update(&replay).unwrap();
    }
    straight.act(&[0.1; 5], false, &mut action); // acting draws from the RNG too
    resumed.act(&[0.1; 5], false, &mut action);
    let bytes = resumed.to_safetensors();
    let mut resumed = Sac::from_safetensors(&bytes).expect("reads its own checkpoint");
    assert_eq!(resumed.updates(), 5);
    assert_eq!(resumed.config(), straight.config());
    for _ in 0..7 {
        straight.update(&replay).unwrap();
        resumed.update(&replay).unwrap();
    }
    assert_eq!(straight.updates(), 12);
    // Every parameter, Adam moment, counter and the RNG state, byte for byte.
    assert_same_checkpoint(&straight.to_safetensors(), &resumed.to_safetensors());
    let (mut a, mut b) = ([0.0f32; 2], [0.0f32; 2]);
    straight.act(&[0.3; 5], false, &mut a);
    resumed.act(&[0.3; 5], false, &mut b);
    assert_eq!(a, b, "same RNG state after loading");
    (straight, bytes)
}

#[test]
fn resuming_from_a_checkpoint_is_bit_identical_to_never_stopping() {
    resume_is_bit_identical(resumable_config(false));
    // And the checkpoint is not trivially the same as a fresh learner.
    assert_ne!(
        Sac::new(5, 2, small_config(true), 7).to_safetensors().len(),
        0
    );
}

/// `critic_layer_norm`: the env critics' and their targets' norms go into the checkpoint under
/// PyTorch's names, the actor's and the human critic's networks have none, and a resumed learner
/// goes on bit for bit.
#[test]
fn a_learner_with_layer_normed_critics_resumes_bit_identically() {
    let (mut normed, bytes) = resume_is_bit_identical(resumable_config(true));
    let names: Vec<String> = safetensors::SafeTensors::deserialize(&bytes)
        .unwrap()
        .names()
        .into_iter()
        .map(str::to_string)
        .collect();
    for net in ["q1", "q2", "q1_target", "q2_target"] {
        for tensor in [
            "norms.0.weight",
            "norms.0.bias",
            "norms.1.weight",
            "norms.1.bias",
        ] {
            let name = format!("{net}.{tensor}");
            assert!(names.contains(&name), "{name} missing from {names:?}");
        }
    }
    for net in ["actor", "h1", "h2"] {
        assert!(
            !names.iter().any(|n| n.starts_with(&format!("{net}.norms"))),
            "{net} has no layer norm: {names:?}"
        );
    }
    let resumed = Sac::from_safetensors(&bytes).expect("reads its own checkpoint");
    assert!(resumed.config().critic_layer_norm);
    // Another learner than the plain one from the same seed.
    let (mut plain, _) = resume_is_bit_identical(resumable_config(false));
    let (mut a, mut b) = ([0.0f32; 2], [0.0f32; 2]);
    normed.act(&[0.3; 5], true, &mut a);
    plain.act(&[0.3; 5], true, &mut b);
    assert_ne!(a, b, "the norms change what the actor learns");
}

#[test]
fn checkpoint_names_tensors_like_pytorch() {
    let sac = Sac::new(3, 1, small_config(true), 0);
    let bytes = sac.to_safetensors();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let names = st.names();
    for name in [
        "actor.layers.0.weight",
        "actor.layers.2.bias",
        "q1.layers.0.weight",
        "q2.layers.1.bias",
        "q1_target.layers.2.weight",
        "q2_target.layers.0.bias",
        "h1.layers.0.weight",
        "h2.layers.2.bias",
        "log_ent_coef",
        "optimizer.critic.1.exp_avg_sq",
        "optimizer.human_critic.0.exp_avg",
    ] {
        assert!(names.contains(&name), "{name} missing from {names:?}");
    }
    assert_eq!(st.tensor("actor.layers.0.weight").unwrap().shape(), [32, 3]);
    let plain = Sac::new(3, 1, small_config(false), 0).to_safetensors();
    let plain = safetensors::SafeTensors::deserialize(&plain).unwrap();
    assert!(plain.names().iter().all(|n| !n.starts_with("h1.")));
}

#[test]
fn corrupt_or_truncated_checkpoints_are_errors_not_panics() {
    let mut config = small_config(true);
    config.hidden = vec![4];
    config.batch_size = 8;
    let mut sac = Sac::new(3, 1, config, 0);
    sac.update(&random_replay(3, 1, 20, 2)).unwrap();
    let bytes = sac.to_safetensors();
    assert!(Sac::from_safetensors(&bytes).is_ok());
    assert!(Sac::from_safetensors(&[]).is_err());
    assert!(Sac::from_safetensors(b"not a checkpoint at all").is_err());
    for len in (0..bytes.len()).step_by(3) {
        assert!(
            Sac::from_safetensors(&bytes[..len]).is_err(),
            "truncated to {len} bytes"
        );
    }
    for (i, flip) in (0..bytes.len()).zip([0x01u8, 0x55, 0x80, 0xff].into_iter().cycle()) {
        let mut corrupt = bytes.clone();
        corrupt[i] ^= flip;
        // A flip in the header's space padding can leave valid JSON; nothing else may load.
        if let Ok(loaded) = Sac::from_safetensors(&corrupt) {
            assert_same_checkpoint(&loaded.to_safetensors(), &bytes);
        }
    }
    let err = Sac::from_safetensors(&bytes[..bytes.len() - 1]).unwrap_err();
    assert!(!err.to_string().is_empty());
}

// --- learning ------------------------------------------------------------------------------

/// A continuous contextual bandit: observe a goal g in [-0.8, 0.8], act a, reward -(a - g)^2,
/// episode over. The deterministic action tanh(mu(g)) must find g.
fn bandit(config: SacConfig, steps: usize, reward_scale: f32, feedback: bool) -> f32 {
    let mut sac = Sac::new(1, 1, config, 11);
    let mut replay = ReplayBuffer::new(steps, 1, 1);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut action = [0.0f32];
    for _ in 0..steps {
        let goal = [rng.random_range(-0.8f32..0.8)];
        sac.act(&goal, false, &mut action);
        let error = action[0] - goal[0];
        replay.push(Transition {
            obs: &goal,
            action: &action,
            reward: -reward_scale * error * error,
            // A synthetic trainer: +1 near the goal, -1 elsewhere.
            human: if !feedback {
                0.0
            } else if error.abs() < 0.15 {
                1.0
            } else {
                -1.0
            },
            next_obs: &goal,
            terminated: true,
        });
        sac.update(&replay);
    }
    let grid: Vec<f32> = (0..17).map(|i| -0.8 + 0.1 * i as f32).collect();
    let mean_error = grid
        .iter()
        .map(|&g| {
            sac.act(&[g], true, &mut action);
            (action[0] - g).abs()
        })
        .sum::<f32>()
        / grid.len() as f32;
    eprintln!("mean |tanh(mu(g)) - g| after {steps} updates: {mean_error:.3}");
    mean_error
}

#[test]
fn sac_learns_a_continuous_bandit() {
    let mean_error = bandit(small_config(false), 3000, 1.0, false);
    assert!(mean_error < 0.1, "mean error {mean_error}");
}

#[test]
fn dref_learns_the_bandit_from_human_feedback_alone() {
    // No reward at all: only H (0.9 of the actor's objective) says where the goal is.
    let mean_error = bandit(small_config(true), 3000, 0.0, true);
    assert!(mean_error < 0.1, "mean error {mean_error}");
}
