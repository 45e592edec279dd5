//! Soft Actor-Critic (Haarnoja et al. 2018) with DREF's human critic H(s, a) (Zhang et al.,
//! CoRL 2022, section 3.2), in stable-baselines3's order, which the authors' fork uses.
//!
//! Read it like CleanRL's `sac_continuous_action.py`:
//!
//! - [`config`]: [`SacConfig`], the per-task hyper-parameters and `--set` overrides.
//! - this file: [`Sac`], its networks and optimisers, acting and the critics' estimates.
//! - `update`: one gradient step, top to bottom: temperature, critics (Eq. 4), human critics
//!   (Eq. 3), actor (Eq. 5), Polyak.
//! - `buffers`: what a gradient step writes, allocated once.
//! - [`checkpoint`]: everything needed to resume, as safetensors bytes.
//! - `flops`: [`mflop_per_update`], the arithmetic of one update, and what the actor loss skips
//!   of it ([`mflop_skipped_per_update`]), for the benchmark.
//! - [`refit`]: the human critic fitted again from fresh heads on a replay's answers alone, to
//!   measure what the answers teach apart from the run (`sim --judge --refit-critic`).
//!
//! No IO here: a checkpoint is bytes, written by the caller.

mod buffers;
pub mod checkpoint;
pub mod config;
mod flops;
pub mod refit;
mod update;

#[cfg(test)]
mod tests;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::Serialize;

use super::replay::ReplayBuffer;
use super::squashed_gaussian;
use super::{Adam, AdamConfig, Mlp, MlpWorkspace};
use buffers::{StepBuffers, fill_critic_input};

pub use checkpoint::CheckpointError;
pub use config::{ActorMix, CriticLoss, HumanCriticConfig, SacConfig};
pub use flops::{mflop_per_update, mflop_skipped_per_update};
pub use refit::{Refit, RefitError, RefitReport};

/// Losses and temperature of an update, averaged over its gradient steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct UpdateStats {
    pub critic_loss: f32,
    pub actor_loss: f32,
    /// 0 without a human critic (or, masked, when no sampled row had feedback).
    pub human_critic_loss: f32,
    /// alpha as used in this update (taken before the temperature step, as SB3 does).
    pub ent_coef: f32,
    pub ent_coef_loss: f32,
}

/// DREF's human critic: twin heads H_1, H_2 on `[s; a]`, no target networks (H is regressed on
/// the immediate feedback, Eq. 3), and their own Adam.
#[derive(Clone, Debug)]
struct HumanCritic {
    h1: Mlp,
    h2: Mlp,
    optimizer: Adam,
}

impl HumanCritic {
    /// Fresh heads on `[s; a]` of `width` inputs (PyTorch's initialisation, H_1 then H_2 from
    /// `rng`).
    fn draw_heads(width: usize, hidden: &[usize], rng: &mut ChaCha8Rng) -> (Mlp, Mlp) {
        let h1 = Mlp::new(width, hidden, 1, rng);
        let h2 = Mlp::new(width, hidden, 1, rng);
        (h1, h2)
    }

    /// The heads with a fresh Adam of step size `learning_rate`.
    fn with_fresh_optimizer((h1, h2): (Mlp, Mlp), learning_rate: f32) -> Self {
        Self {
            optimizer: Adam::new(
                AdamConfig::with_lr(f64::from(learning_rate)),
                &[h1.params().len(), h2.params().len()],
            ),
            h1,
            h2,
        }
    }
}

/// A SAC learner: tanh-Gaussian actor, twin Q critics with Polyak targets, automatic entropy
/// temperature, and optionally DREF's twin human critic. Owns its RNG (batch sampling and all
/// policy noise), so a seed and the sequence of calls determine everything.
#[derive(Clone, Debug)]
pub struct Sac {
    config: SacConfig,
    obs_dim: usize,
    act_dim: usize,
    /// SB3: `-dim(A)` unless configured.
    target_entropy: f32,
    /// `obs_dim -> hidden -> 2 dim(A)`: `[mu; log_std]` per sample.
    actor: Mlp,
    q1: Mlp,
    q2: Mlp,
    q1_target: Mlp,
    q2_target: Mlp,
    human_critic: Option<HumanCritic>,
    /// log alpha, learned (SB3's `log_ent_coef`).
    log_ent_coef: f32,
    actor_optimizer: Adam,
    /// One optimiser over both critics (SB3's `critic.optimizer`).
    critic_optimizer: Adam,
    ent_coef_optimizer: Adam,
    rng: ChaCha8Rng,
    /// Gradient steps taken.
    updates: u64,
    buffers: StepBuffers,
    /// Batch-1 workspaces for acting and for the critics' estimates.
    act_ws: MlpWorkspace,
    eval_ws: MlpWorkspace,
    act_noise: Vec<f32>,
    /// The answered mix's weight on unanswered rows as the run sets it for now (the gate of
    /// `answered_after`), in place of the config's `unanswered`; not checkpointed: the run
    /// sets it before every update.
    unanswered_override: Option<f32>,
}

impl Sac {
    /// Networks with PyTorch's default initialisation, drawn from `seed` in the order actor,
    /// q1, q2 (h1, h2); targets start as copies.
    pub fn new(obs_dim: usize, act_dim: usize, config: SacConfig, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let hidden = &config.hidden;
        let actor = Mlp::new(obs_dim, hidden, 2 * act_dim, &mut rng);
        let env_critic = |rng: &mut ChaCha8Rng| {
            let q = Mlp::new(obs_dim + act_dim, hidden, 1, rng);
            // Layer norms draw nothing: the same seed gives the same layers with or without.
            if config.critic_layer_norm {
                q.with_layer_norm()
            } else {
                q
            }
        };
        let q1 = env_critic(&mut rng);
        let q2 = env_critic(&mut rng);
        let human = config
            .human_critic
            .is_some()
            .then(|| HumanCritic::draw_heads(obs_dim + act_dim, hidden, &mut rng));
        Self::from_parts(obs_dim, act_dim, config, actor, [q1, q2], human, rng)
    }

    /// Assemble a learner around given online networks: targets copy the critics, optimisers
    /// start fresh, log alpha = ln(init_ent_coef).
    fn from_parts(
        obs_dim: usize,
        act_dim: usize,
        config: SacConfig,
        actor: Mlp,
        [q1, q2]: [Mlp; 2],
        human: Option<(Mlp, Mlp)>,
        rng: ChaCha8Rng,
    ) -> Self {
        assert!(obs_dim > 0 && act_dim > 0, "empty observation or action");
        assert!(config.batch_size > 0, "batch_size must be positive");
        let adam = || AdamConfig::with_lr(f64::from(config.learning_rate));
        let human_critic =
            human.map(|heads| HumanCritic::with_fresh_optimizer(heads, config.learning_rate));
        let buffers = StepBuffers::new(
            obs_dim,
            act_dim,
            config.batch_size,
            &actor,
            &q1,
            human_critic.is_some(),
            config
                .human_critic
                .as_ref()
                .is_some_and(|c| c.answer_replay),
        );
        Self {
            target_entropy: config.target_entropy.unwrap_or(-(act_dim as f32)),
            log_ent_coef: config.init_ent_coef.ln(),
            actor_optimizer: Adam::new(adam(), &[actor.params().len()]),
            critic_optimizer: Adam::new(adam(), &[q1.params().len(), q2.params().len()]),
            ent_coef_optimizer: Adam::new(adam(), &[1]),
            q1_target: q1.clone(),
            q2_target: q2.clone(),
            act_ws: actor.workspace(1),
            eval_ws: q1.workspace(1),
            act_noise: vec![0.0; act_dim],
            unanswered_override: None,
            updates: 0,
            buffers,
            human_critic,
            actor,
            q1,
            q2,
            rng,
            obs_dim,
            act_dim,
            config,
        }
    }

    pub fn config(&self) -> &SacConfig {
        &self.config
    }

    /// With the answered mix: read H on unanswered rows at this share of its weight from the
    /// next update on (`None`: the config's `unanswered`).
    pub fn set_unanswered_override(&mut self, weight: Option<f32>) {
        self.unanswered_override = weight;
    }

    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    pub fn act_dim(&self) -> usize {
        self.act_dim
    }

    /// Gradient steps taken so far.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// The state of the generator behind sampled actions and minibatches (also in
    /// [`Sac::to_safetensors`]); an expert that only acts needs nothing else to resume.
    pub fn rng_state(&self) -> crate::rl::rng_state::RngState {
        crate::rl::rng_state::RngState::of(&self.rng)
    }

    pub fn restore_rng(
        &mut self,
        state: &crate::rl::rng_state::RngState,
    ) -> Result<(), crate::rl::rng_state::RngStateError> {
        self.rng = state.restore()?;
        Ok(())
    }

    /// The entropy temperature alpha = exp(log_ent_coef).
    pub fn ent_coef(&self) -> f32 {
        self.log_ent_coef.exp()
    }

    /// Policy action in `[-1, 1]^act_dim` for one observation: sampled, or `tanh(mu)` if
    /// deterministic.
    pub fn act(&mut self, obs: &[f32], deterministic: bool, action: &mut [f32]) {
        assert_eq!(obs.len(), self.obs_dim, "observation size");
        assert_eq!(action.len(), self.act_dim, "action size");
        self.act_ws.input_mut().as_mut_slice().copy_from_slice(obs);
        self.actor.forward(&mut self.act_ws);
        let head = self.act_ws.output().as_slice();
        if deterministic {
            squashed_gaussian::mean_action(head, action);
        } else {
            for e in &mut self.act_noise {
                *e = self.rng.sample(StandardNormal);
            }
            squashed_gaussian::sample(head, &self.act_noise, action);
        }
    }

    /// `min_j Q_j(s, a)`: the expert oracle uses this as Q*.
    pub fn q_value(&mut self, obs: &[f32], action: &[f32]) -> f32 {
        let (q1, q2) = (&self.q1, &self.q2);
        min_of_twins(&mut self.eval_ws, [q1, q2], obs, action)
    }

    /// Whether the learner has a human critic (a run that learns from answers).
    pub fn has_human_critic(&self) -> bool {
        self.human_critic.is_some()
    }

    /// `min_j H_j(s, a)`, DREF's H_hat (0.0 without a human critic).
    pub fn human_estimate(&mut self, obs: &[f32], action: &[f32]) -> f32 {
        match &self.human_critic {
            Some(HumanCritic { h1, h2, .. }) => {
                min_of_twins(&mut self.eval_ws, [h1, h2], obs, action)
            }
            None => 0.0,
        }
    }

    /// `gradient_steps` gradient steps on batches sampled from `replay`; `None` (nothing done)
    /// while `replay.len() < max(learning_starts, 1)`.
    pub fn update(&mut self, replay: &ReplayBuffer) -> Option<UpdateStats> {
        assert!(
            replay.obs_dim() == self.obs_dim && replay.act_dim() == self.act_dim,
            "replay of (obs {}, act {}) for a learner of (obs {}, act {})",
            replay.obs_dim(),
            replay.act_dim(),
            self.obs_dim,
            self.act_dim
        );
        let steps = self.config.gradient_steps;
        if replay.len() < self.config.learning_starts.max(1) || steps == 0 {
            return None;
        }
        let mut sum = UpdateStats::default();
        for _ in 0..steps {
            self.sample_batch_and_noise(replay);
            let s = self.gradient_step();
            sum.critic_loss += s.critic_loss;
            sum.actor_loss += s.actor_loss;
            sum.human_critic_loss += s.human_critic_loss;
            sum.ent_coef += s.ent_coef;
            sum.ent_coef_loss += s.ent_coef_loss;
        }
        let n = steps as f32;
        Some(UpdateStats {
            critic_loss: sum.critic_loss / n,
            actor_loss: sum.actor_loss / n,
            human_critic_loss: sum.human_critic_loss / n,
            ent_coef: sum.ent_coef / n,
            ent_coef_loss: sum.ent_coef_loss / n,
        })
    }

    /// Draw the minibatch, then the policy noise at s and at s', then (with `answer_replay`)
    /// the human critic's minibatch of answered transitions: all the randomness of a step.
    /// Without `answer_replay` the draws are those of the runs before it, to the bit.
    fn sample_batch_and_noise(&mut self, replay: &ReplayBuffer) {
        let b = &mut self.buffers;
        replay.sample(&mut self.rng, &mut b.batch);
        for e in b.noise_pi.iter_mut().chain(b.noise_next.iter_mut()) {
            *e = self.rng.sample(StandardNormal);
        }
        if let Some(answers) = &mut b.answer_batch {
            replay.sample_answered(&mut self.rng, answers);
        }
    }
}

/// `min(f_1(s, a), f_2(s, a))` for one sample, through a batch-1 workspace.
fn min_of_twins(ws: &mut MlpWorkspace, nets: [&Mlp; 2], obs: &[f32], action: &[f32]) -> f32 {
    fill_critic_input(ws, obs, action);
    let mut values = [0.0f32; 2];
    for (value, net) in values.iter_mut().zip(nets) {
        net.forward(ws);
        *value = ws.output()[0];
    }
    values[0].min(values[1])
}
