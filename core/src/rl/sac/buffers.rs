//! Every buffer one gradient step writes, allocated once by [`crate::rl::sac::Sac::new`] so that
//! `update` allocates nothing of its own. None of it carries state from one step to the next.

use crate::rl::replay::Batch;
use crate::rl::{Mlp, MlpWorkspace};

/// Per-sample vectors are sample-major (`batch x dim`, one sample after another), which is also
/// the column-major `dim x batch` layout of the networks' activations.
#[derive(Clone, Debug)]
pub(super) struct StepBuffers {
    /// The sampled minibatch `(s, a, r, H, s', terminated)`.
    pub batch: Batch,
    /// With `answer_replay`: the human critic's own minibatch, drawn from answered transitions
    /// (H all 0 while nothing is answered).
    pub answer_batch: Option<Batch>,
    /// Standard normal noise of the policy sample at s (`a_pi`) and at s' (`next_actions`).
    pub noise_pi: Vec<f32>,
    pub noise_next: Vec<f32>,
    /// `a_pi ~ pi(.|s)` with its log-probability, reused by the temperature and actor losses.
    pub a_pi: Vec<f32>,
    pub log_pi: Vec<f32>,
    /// `a' ~ pi(.|s')` with its log-probability, for the target.
    pub next_actions: Vec<f32>,
    pub next_log_pi: Vec<f32>,
    /// The critics' regression target `y = r + gamma (1 - terminated) next_q_value` (Eq. 4).
    pub target_q_values: Vec<f32>,
    /// dL_actor / d a_pi, summed over the critics that reach the actor loss.
    pub dl_da: Vec<f32>,
    /// The actor at s; kept from the first forward pass until the actor's backward pass.
    pub actor_ws: MlpWorkspace,
    /// The actor at s'.
    pub next_actor_ws: MlpWorkspace,
    /// One workspace per critic (q1 and its target share `q1_ws`, likewise q2): in the actor
    /// loss all four forward passes must be kept until their backward passes.
    pub q1_ws: MlpWorkspace,
    pub q2_ws: MlpWorkspace,
    /// `None` without a human critic.
    pub h_ws: Option<[MlpWorkspace; 2]>,
    /// Which head of each twin pair the actor loss's `min` picked, per sample: the environment
    /// critics' and the human critics'. Its gradient reaches each head through those samples only.
    pub picks_q: TwinPicks,
    pub picks_h: TwinPicks,
    /// Where a frozen critic passes the actor loss's gradient back through its picked samples:
    /// one per twin, since the twins do so side by side.
    pub picked_ws: [MlpWorkspace; 2],
}

/// The samples of a batch split between the two heads of a twin pair, in order, in buffers
/// allocated once.
#[derive(Clone, Debug)]
pub(super) struct TwinPicks {
    heads: [Vec<usize>; 2],
    len: [usize; 2],
}

impl TwinPicks {
    fn new(batch_size: usize) -> Self {
        Self {
            heads: [vec![0; batch_size], vec![0; batch_size]],
            len: [0; 2],
        }
    }

    pub fn clear(&mut self) {
        self.len = [0; 2];
    }

    /// Sample `i` goes to the first head if `first`, else to the second.
    pub fn push(&mut self, i: usize, first: bool) {
        let j = usize::from(!first);
        self.heads[j][self.len[j]] = i;
        self.len[j] += 1;
    }

    /// The samples of head `j` (0 or 1), in increasing order.
    pub fn head(&self, j: usize) -> &[usize] {
        &self.heads[j][..self.len[j]]
    }
}

impl StepBuffers {
    pub fn new(
        obs_dim: usize,
        act_dim: usize,
        batch_size: usize,
        actor: &Mlp,
        critic: &Mlp,
        human_critic: bool,
        answer_replay: bool,
    ) -> Self {
        let per_action = vec![0.0; batch_size * act_dim];
        let per_sample = vec![0.0; batch_size];
        Self {
            batch: Batch::new(batch_size, obs_dim, act_dim),
            answer_batch: (human_critic && answer_replay)
                .then(|| Batch::new(batch_size, obs_dim, act_dim)),
            noise_pi: per_action.clone(),
            noise_next: per_action.clone(),
            a_pi: per_action.clone(),
            log_pi: per_sample.clone(),
            next_actions: per_action.clone(),
            next_log_pi: per_sample.clone(),
            target_q_values: per_sample,
            dl_da: per_action,
            actor_ws: actor.workspace(batch_size),
            next_actor_ws: actor.workspace(batch_size),
            q1_ws: critic.workspace(batch_size),
            q2_ws: critic.workspace(batch_size),
            h_ws: human_critic
                .then(|| [critic.workspace(batch_size), critic.workspace(batch_size)]),
            picks_q: TwinPicks::new(batch_size),
            picks_h: TwinPicks::new(batch_size),
            picked_ws: [critic.workspace(batch_size), critic.workspace(batch_size)],
        }
    }
}

/// Write the critic input `[s; a]`, one column per sample.
pub(super) fn fill_critic_input(ws: &mut MlpWorkspace, obs: &[f32], actions: &[f32]) {
    let batch = ws.batch();
    let (obs_dim, act_dim) = (obs.len() / batch, actions.len() / batch);
    let columns = ws
        .input_mut()
        .as_mut_slice()
        .chunks_exact_mut(obs_dim + act_dim);
    for ((column, s), a) in columns
        .zip(obs.chunks_exact(obs_dim))
        .zip(actions.chunks_exact(act_dim))
    {
        column[..obs_dim].copy_from_slice(s);
        column[obs_dim..].copy_from_slice(a);
    }
}
