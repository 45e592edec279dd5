//! The human critic fitted again, apart from the run: fresh heads trained on a replay's answered
//! transitions alone, in batches of nothing but answers. A run's own critic learnt its answers
//! beside everything else the run did (masked rows among the learner's batches, as the answers
//! came); a refit on the same answers says what those answers can teach by themselves, and a
//! refit on another run's first answers, as many, says what their placement is worth
//! (`dualrep sim --judge --refit-critic`).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::rl::kernels::side_by_side;
use crate::rl::loss::Regression;
use crate::rl::replay::{Batch, ReplayBuffer};
use crate::rl::{Mlp, MlpWorkspace};

use super::buffers::fill_critic_input;
use super::update::regress;
use super::{HumanCritic, Sac};

/// How to refit: gradient steps, how many of the replay's answers (the first, by time), and the
/// seed of the fresh heads and of the batches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refit {
    pub updates: u64,
    /// `None`: every answered transition.
    pub answers: Option<usize>,
    pub seed: u64,
}

/// What a refit used and reached.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RefitReport {
    pub updates: u64,
    /// The answered transitions the batches were drawn from.
    pub answers: usize,
    /// `0.5 (mse_1 + mse_2)` over the last 100 gradient steps' batches.
    pub final_loss: f32,
}

/// Why a refit cannot run.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum RefitError {
    #[error("the learner has no human critic to refit")]
    NoHumanCritic,
    #[error("the replay holds no answered transition")]
    NoAnswers,
    #[error("{asked} answers asked for; the replay holds {held}")]
    TooFewAnswers { asked: usize, held: usize },
    #[error("0 answers: a refit needs at least one")]
    ZeroAnswers,
    #[error(
        "the replay is full ({0} transitions): its slots may have wrapped, so the first answers by slot are not the first by time"
    )]
    MayHaveWrapped(usize),
    #[error("0 updates: a refit needs at least one gradient step")]
    NoUpdates,
    #[error(
        "a replay of (obs {replay_obs}, act {replay_act}) for a learner of (obs {obs}, act {act})"
    )]
    Dimensions {
        replay_obs: usize,
        replay_act: usize,
        obs: usize,
        act: usize,
    },
}

impl Sac {
    /// Replace the human critic by fresh heads (PyTorch's initialisation, drawn from
    /// `refit.seed`) with a fresh Adam at the run's learning rate, trained `refit.updates`
    /// gradient steps of the run's batch size on `replay`'s answered transitions (H != 0; the
    /// first `refit.answers` by time, if given), each step as the run's step 5 takes it on a
    /// batch of answers: `0.5 sum_j mse(H_j(s, a), H)`. The actor, the environment critics and
    /// the temperature are left as they are.
    pub fn refit_human_critic(
        &mut self,
        replay: &ReplayBuffer,
        refit: Refit,
    ) -> Result<RefitReport, RefitError> {
        if self.human_critic.is_none() {
            return Err(RefitError::NoHumanCritic);
        }
        if (replay.obs_dim(), replay.act_dim()) != (self.obs_dim, self.act_dim) {
            return Err(RefitError::Dimensions {
                replay_obs: replay.obs_dim(),
                replay_act: replay.act_dim(),
                obs: self.obs_dim,
                act: self.act_dim,
            });
        }
        if refit.updates == 0 {
            return Err(RefitError::NoUpdates);
        }
        let held = replay.answered_len();
        let answers = match refit.answers {
            None if held == 0 => return Err(RefitError::NoAnswers),
            None => held,
            Some(0) => return Err(RefitError::ZeroAnswers),
            Some(asked) if asked > held => return Err(RefitError::TooFewAnswers { asked, held }),
            Some(_) if replay.len() == replay.capacity() => {
                return Err(RefitError::MayHaveWrapped(replay.len()));
            }
            Some(asked) => asked,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(refit.seed);
        let heads =
            HumanCritic::draw_heads(self.obs_dim + self.act_dim, &self.config.hidden, &mut rng);
        let HumanCritic {
            mut h1,
            mut h2,
            mut optimizer,
        } = HumanCritic::with_fresh_optimizer(heads, self.config.learning_rate);
        let size = self.config.batch_size;
        let mut batch = Batch::new(size, self.obs_dim, self.act_dim);
        let (mut ws1, mut ws2) = (h1.workspace(size), h2.workspace(size));
        let mut recent = Vec::with_capacity(100);
        for step in 0..refit.updates {
            replay.sample_answered_first(&mut rng, &mut batch, answers);
            // The twins side by side, as the run's step 5 takes them.
            let fit = |h: &mut Mlp, ws: &mut MlpWorkspace| {
                fill_critic_input(ws, &batch.obs, &batch.actions);
                regress(h, ws, &batch.human, Regression::Mse)
            };
            let (first, second) =
                side_by_side(|| fit(&mut h1, &mut ws1), || fit(&mut h2, &mut ws2));
            optimizer.step([h1.params_and_grads(), h2.params_and_grads()]);
            if refit.updates - step <= 100 {
                recent.push(0.5 * (first + second));
            }
        }
        self.human_critic = Some(HumanCritic { h1, h2, optimizer });
        Ok(RefitReport {
            updates: refit.updates,
            answers,
            final_loss: recent.iter().sum::<f32>() / recent.len() as f32,
        })
    }
}
