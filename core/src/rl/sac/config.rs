//! SAC's hyper-parameters, per task (`algorithms.md` section 1, from the authors' configs), and
//! DREF's human critic (section 2). Overrides by name come through `crate::settings`.

use serde::{Deserialize, Serialize};

use crate::sim::Task;

/// Everything that shapes one SAC learner. [`SacConfig::for_task`] gives the published values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SacConfig {
    /// Hidden layer sizes of the actor and of every critic (ReLU between layers).
    pub hidden: Vec<usize>,
    /// Adam's learning rate for the actor, the critics, the human critics and the temperature.
    pub learning_rate: f32,
    pub batch_size: usize,
    /// Replay capacity (the caller owns the [`crate::rl::replay::ReplayBuffer`]; this is its size).
    pub buffer_size: usize,
    /// Polyak coefficient: `target = (1 - tau) target + tau online`.
    pub tau: f32,
    pub gamma: f32,
    /// No update until the replay holds this many transitions (and at least one).
    pub learning_starts: usize,
    /// Gradient steps per call of [`crate::rl::sac::Sac::update`] (one per environment step).
    pub gradient_steps: usize,
    /// Initial entropy temperature alpha (SB3's `ent_coef = "auto_1.0"`).
    pub init_ent_coef: f32,
    /// `None`: SB3's default `-dim(A)`.
    pub target_entropy: Option<f32>,
    /// DREF's human critic H(s, a); `None` is plain SAC.
    pub human_critic: Option<HumanCriticConfig>,
    /// How the environment critics fit their targets. Left out of a run's config while mse,
    /// so earlier configs read as they were.
    #[serde(default, skip_serializing_if = "CriticLoss::is_mse")]
    pub critic_loss: CriticLoss,
    /// Our choice (the setting `critic_layer_norm`), a learner of its own: the environment
    /// critics (and their targets) normalise each hidden layer before its ReLU
    /// ([`crate::rl::Mlp::with_layer_norm`], PyTorch's `Linear -> LayerNorm -> ReLU`). On Lunar
    /// Lander the runs that end lowest are those whose env critic values the policy far above
    /// anything it earns, with the mse loss and with Huber alike; a normalised critic cannot
    /// reach ever larger values on inputs unlike its data without growing its last layer, the
    /// overestimation that layer norm curbs in SAC's critics (Ball et al. 2023; Nauman et al.
    /// 2024). The actor and the human critic stay as they are. Left out of a run's config while
    /// off, so earlier configs read as they were.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub critic_layer_norm: bool,
}

/// The loss the environment critics Q_1, Q_2 regress their soft Bellman targets with (Eq. 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum CriticLoss {
    /// Mean squared error: stable-baselines3's SAC and the authors'.
    #[default]
    Mse,
    /// Our choice (the setting `critic_loss = "huber"`), a learner of its own: the Huber loss
    /// at delta 1 (PyTorch's `F.huber_loss`, the loss SB3's DQN fits its Q with). On Lunar
    /// Lander the runs that end lowest are the ones whose env critic's loss ran away (up to 2,000
    /// against 10-100 on the runs that land; docs/dref-lunar-lander.md, "What decides a Lunar
    /// Lander run"), which no query rule reaches; Huber bounds each sample's pull on the critic, so
    /// a crash's -100 or a target that ran ahead moves it no more than any sample off by 1.
    Huber,
}

impl CriticLoss {
    fn is_mse(&self) -> bool {
        *self == Self::Mse
    }
}

/// DREF's human critic: twin heads regressed on the immediate feedback H (Eq. 3) and mixed into
/// the actor's objective (Eq. 5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HumanCriticConfig {
    /// Weight of H against Q in the actor loss (the authors: 9, as `0.1 Q + 0.9 H`).
    pub lambda: f32,
    pub mix: ActorMix,
    /// `human_critic_mask` (our choice, `algorithms.md`): regress H only on rows that received feedback (H != 0).
    /// The authors train on every sampled row, the H = 0 ones included (false).
    pub mask: bool,
    /// `human_critic_anchor` (our choice, with `mask`): how hard the rows without feedback pull
    /// H towards 0, as a weight on their own mean squared error beside the answered rows' (0:
    /// the plain mask). Masked, the critic at a few percent of feedback extrapolates its answers
    /// to states nobody judged, and the actor, which weighs H nine times Q, follows it there;
    /// anchored, H stays near 0 (and the actor follows Q) where there are no answers, while the
    /// answers keep their own weight however much they are outnumbered.
    #[serde(default)]
    pub anchor: f32,
    /// `mix_unanswered` (our choice, with [`ActorMix::Answered`]): the share of H's weight the
    /// actor keeps on sampled rows nobody answered, between the answered mix's 0 (follow Q
    /// only where there is no answer) and the authors' 1 (follow the critic's extrapolation
    /// everywhere). Left out of a run's config while 0, so earlier configs read as they were.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub unanswered: f32,
    /// `mix_answered_after` (our choice, with [`ActorMix::Answered`]): until the run's N-th
    /// successful episode the actor reads H on unanswered rows at full weight (the authors'
    /// mix), and only then as `unanswered` says. A learner the environment has not yet
    /// rewarded has nothing but the critic's extrapolation of a few answers to follow (a
    /// sparse task such as Placing); once it has succeeded, Q carries the way and H is read
    /// where people answered. 0: no gate. Left out of a run's config while 0.
    #[serde(default, skip_serializing_if = "is_zero_count")]
    pub answered_after: u32,
    /// `mix_agree_within` (our choice, with [`ActorMix::Answered`]): on an unanswered row where
    /// the two heads of H differ by at most this much, the actor reads H at full weight, as
    /// on an answered one. H is in the answers' units (+1 / -1), so one number serves every
    /// task: where the heads agree the answers around constrain H, where they part it is
    /// extrapolating and the actor follows Q. 0: off. Left out of a run's config while 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub agree_within: f32,
    /// `mix_failure_window` (our choice, with [`ActorMix::Answered`]): the actor reads H on
    /// unanswered rows at the share of the run's last N episodes that failed (at least
    /// `unanswered`; episodes not yet run count as failed). `answered_after` shuts H's
    /// extrapolation off for good at the N-th success, and on Placing the learner then lost
    /// the task; this gate follows the learner both ways: while it fails it follows the
    /// critic's extrapolation of the answers, as it succeeds it follows Q where nobody
    /// answered. 0: off. Left out of a run's config while 0.
    #[serde(default, skip_serializing_if = "is_zero_count")]
    pub failure_window: u32,
    /// `mix_authors_until` (our choice, with [`ActorMix::Answered`]): until the run's step N
    /// the actor reads H on every sampled row at full weight (the authors' mix), and as the
    /// answered mix after it. Lunar Lander's opening answers 0.45 of every state's visits for
    /// its first 30,000 steps, so H is constrained wherever the learner goes while it lasts;
    /// the answered mix leaves the actor to Q alone on the other rows, and on two of its ten
    /// seeds the env critic ran away inside the opening, which EF-100 (H on every row) did not
    /// on the same seeds. 0: off. Left out of a run's config while 0.
    #[serde(default, skip_serializing_if = "is_zero_steps")]
    pub authors_until: u64,
    /// `mix_authors_fade` (our choice, with [`ActorMix::Answered`]): after `authors_until`,
    /// H's weight on unanswered rows falls in a straight line from 1 to `unanswered` over this
    /// many steps, rather than at once. With the authors' mix through Lunar Lander's opening
    /// the env critic of one seed in two ran away within 10k steps of the switch, the actor
    /// going from H to Q alone on most rows in one step; faded over 30k steps it ran away all
    /// the same, while H was still read (`docs/dref.md`). 0: at once. Left out of a run's
    /// config while 0.
    #[serde(default, skip_serializing_if = "is_zero_steps")]
    pub authors_fade: u64,
    /// `mix_unread_to_q` (our choice, with [`ActorMix::Answered`]): the share of H's weight
    /// the actor does not read on a row goes to Q, so every row's weights sum to 1 (Q alone,
    /// as SAC, where H is not read at all). Without it a row with H unread keeps Q at 0.1: a
    /// tenth of the objective the entropy coefficient was tuned against, so the policy turns
    /// more random until the coefficient catches up. false: off. Left out of a run's config
    /// while off.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub unread_to_q: bool,
    /// `human_critic_answer_replay` (our choice, with `mask`): the human critic regresses a
    /// batch of its own, `batch_size` transitions drawn from the answered ones, instead of
    /// the answered rows of SAC's batch. At a few percent of feedback SAC's batch of 512 holds
    /// about ten answered rows, so the masked critic fits its answers on a fiftieth of the
    /// samples a critic told on every step gets; with its own batch it takes full steps on the
    /// answers as they are, however rare. false: off. Left out of a run's config while off.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub answer_replay: bool,
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

fn is_zero_count(n: &u32) -> bool {
    *n == 0
}

fn is_zero_steps(n: &u64) -> bool {
    *n == 0
}

impl Default for HumanCriticConfig {
    fn default() -> Self {
        Self {
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
        }
    }
}

/// How the actor loss combines the environment critic Q and the human critic H.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum ActorMix {
    /// The authors' code (the published curves): head-wise
    /// `min_j (Q_j + lambda H_j) / (1 + lambda)`, i.e. `min_j(0.1 Q_j + 0.9 H_j)` at lambda = 9.
    Authors,
    /// The paper's Eq. 5: `min_j Q_j + lambda min_j H_j`.
    Paper,
    /// Our choice (the setting `mix = "answered"`): the authors' mix on the sampled rows whose
    /// step was answered (H != 0), and on the others H taken as 0, which is what the authors'
    /// unmasked critic learns there: `min_j(w_q Q_j)`. With the mask the critic no longer
    /// regresses unanswered rows to 0, so it extrapolates a few answers to states nobody judged;
    /// this keeps the actor from following it there, without pulling H itself towards 0.
    /// [`HumanCriticConfig::unanswered`] keeps a share of H's weight on those rows.
    Answered,
}

impl SacConfig {
    /// The per-task table of `algorithms.md` section 1, with DREF's human critic at its defaults.
    pub fn for_task(task: Task) -> Self {
        let (hidden, learning_rate) = match task {
            Task::LunarLander => (vec![400, 300], 7.3e-4),
            Task::Reaching => (vec![64, 64], 7.5e-4),
            Task::Placing => (vec![128, 128], 7.5e-4),
        };
        Self {
            hidden,
            learning_rate,
            batch_size: 512,
            buffer_size: 1_000_000,
            tau: 0.01,
            gamma: 0.99,
            learning_starts: 0,
            gradient_steps: 1,
            init_ent_coef: 1.0,
            target_entropy: None,
            human_critic: Some(HumanCriticConfig::default()),
            critic_loss: CriticLoss::Mse,
            critic_layer_norm: false,
        }
    }
}
