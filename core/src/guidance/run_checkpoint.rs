//! A whole evaluative run as bytes, taken at the start of an episode, so that a long
//! `dualrep train` (a Placing or Lunar Lander run of the Figure 3 grid) stopped midway resumes
//! bit for bit where it was: same learner, same replay rows, same random streams, same env.
//!
//! Only an episode's start is a safe point: the env's physics state is not serialisable, but a
//! fresh episode is fully defined by its reset seed (tests/env_contract.rs pins that down).
//!
//! Layout (no IO here; the caller writes the bytes atomically):
//! `MAGIC`, then a u64 LE length and the run's state as JSON, then a u64 LE length and the
//! learner's safetensors, then the replay rows ([`ReplayBuffer::to_bytes`]) to the end.

use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{EvaluativeRun, EvaluativeRunConfig, EvaluativeTrainer};
use crate::guidance::ask_pacing::AskPacing;
use crate::guidance::evaluative_trainer::RestoreError;
use crate::guidance::feedback_schedule::FeedbackSchedule;
use crate::guidance::mix_gate::MixGate;
use crate::guidance::query_rule::QueryRule;
use crate::rl::kernels::{self, KernelPath};
use crate::rl::replay::{ReplayBuffer, ReplayBytesError, ReplayLayout};
use crate::rl::rng_state::{RngState, RngStateError};
use crate::rl::{CheckpointError, Sac};
use crate::sim::EnvFault;

const MAGIC: &[u8] = b"dualrep-run/1\n";

/// Why bytes do not resume a run; each text begins `run checkpoint: `.
#[derive(Debug, thiserror::Error)]
pub enum RunCheckpointError {
    #[error("run checkpoint: not a dualrep run checkpoint")]
    NotACheckpoint,
    /// The bytes end inside the part named (`state`, `learner`).
    #[error("run checkpoint: truncated {0}")]
    Truncated(&'static str),
    /// The run's state does not read.
    #[error("run checkpoint: state: {0}")]
    State(serde_json::Error),
    /// A remote env that describes itself otherwise than when the run began.
    #[error(
        "run checkpoint: the task or its scene graph is not the one the run was saved with (an env in another process that now declares other predicates, features or sizes?)"
    )]
    OtherSceneGraph,
    #[error("run checkpoint: it belongs to a run with another configuration")]
    OtherConfig,
    #[error("run checkpoint: {0}")]
    Learner(CheckpointError),
    #[error("run checkpoint: {0}")]
    Replay(ReplayBytesError),
    /// The schedule's or the episode seeds' random stream.
    #[error("run checkpoint: {0}")]
    Rng(RngStateError),
    #[error("run checkpoint: {0}")]
    Trainer(RestoreError),
    #[error("run checkpoint: resetting the environment: {0}")]
    Reset(EnvFault),
}

/// Everything of a run at an episode's start except the learner and the replay rows.
#[derive(Serialize, Deserialize)]
struct RunState {
    config: EvaluativeRunConfig,
    steps: u64,
    episodes: u64,
    cumulative_return: f64,
    /// Successful episodes (checkpoints written before it existed read as 0: their runs had
    /// no gate that counts them).
    #[serde(default)]
    successes: u64,
    /// The last episodes' outcomes kept for `failure_window` (checkpoints written before it
    /// existed read as none: their runs had no such gate).
    #[serde(default)]
    mix_gate: MixGate,
    feedback_count: u64,
    no_feedback_count: u64,
    /// Queries a person's pace held back (checkpoints written before it existed read as 0).
    #[serde(default)]
    held_back: u64,
    episode_seed: u64,
    episode_seeds: RngState,
    schedule: ScheduleState,
    queried: Vec<(u64, usize)>,
    /// Replay rows taken in besides the steps (checkpoints written before it existed read as
    /// none).
    #[serde(default)]
    taken_in: u64,
    /// The rule's floods and silences (checkpoints written before it existed read as none).
    #[serde(default)]
    pacing: AskPacing,
    replay: ReplayLayout,
    trainer: serde_json::Value,
    /// Whatever the caller keeps with the run (the CLI: recent episodes, wall time so far).
    notes: serde_json::Value,
    /// The kernels the run computed with; checkpoints written before there was a choice ran on
    /// the portable path.
    #[serde(default = "portable")]
    kernels: KernelPath,
}

fn portable() -> KernelPath {
    KernelPath::Portable
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum ScheduleState {
    Never,
    Random { probability: f64, rng: RngState },
    Dref(QueryRule),
}

impl ScheduleState {
    fn of(schedule: &FeedbackSchedule) -> Self {
        match schedule {
            FeedbackSchedule::Never => Self::Never,
            FeedbackSchedule::Random { probability, rng } => Self::Random {
                probability: *probability,
                rng: RngState::of(rng),
            },
            FeedbackSchedule::Dref(rule) => Self::Dref(rule.clone()),
        }
    }

    fn restore(self) -> Result<FeedbackSchedule, RngStateError> {
        Ok(match self {
            Self::Never => FeedbackSchedule::Never,
            Self::Random { probability, rng } => FeedbackSchedule::Random {
                probability,
                rng: Box::new(rng.restore()?),
            },
            Self::Dref(rule) => FeedbackSchedule::Dref(rule),
        })
    }
}

impl EvaluativeRun {
    /// True between episodes: the moment [`EvaluativeRun::checkpoint`] may be taken.
    pub fn at_episode_start(&self) -> bool {
        self.episode_length == 0
    }

    /// The run and `trainer`'s state as bytes, with the caller's `notes` (returned by
    /// [`EvaluativeRun::resume`]). Panics unless [`Self::at_episode_start`].
    pub fn checkpoint(&self, trainer: &dyn EvaluativeTrainer, notes: serde_json::Value) -> Vec<u8> {
        assert!(
            self.at_episode_start(),
            "a run checkpoint is taken between episodes"
        );
        let (replay, rows) = self.replay.to_bytes();
        let state = RunState {
            config: self.config.clone(),
            steps: self.steps,
            episodes: self.episodes,
            cumulative_return: self.cumulative_return,
            successes: self.successes,
            mix_gate: self.mix_gate.clone(),
            feedback_count: self.feedback_count,
            no_feedback_count: self.no_feedback_count,
            held_back: self.held_back,
            episode_seed: self.episode_seed,
            episode_seeds: RngState::of(&self.episode_seeds),
            schedule: ScheduleState::of(&self.schedule),
            queried: self.queried.clone(),
            taken_in: self.taken_in,
            pacing: self.pacing,
            replay,
            trainer: trainer.checkpoint_state(),
            notes,
            kernels: kernels::current_path(),
        };
        let state = serde_json::to_vec(&state).expect("a run's state serialises");
        let learner = self.learner.to_safetensors();
        let mut bytes =
            Vec::with_capacity(MAGIC.len() + 16 + state.len() + learner.len() + rows.len());
        bytes.extend_from_slice(MAGIC);
        for blob in [&state, &learner] {
            bytes.extend_from_slice(&(blob.len() as u64).to_le_bytes());
            bytes.extend_from_slice(blob);
        }
        bytes.extend_from_slice(&rows);
        bytes
    }

    /// The kernels a checkpoint's run computed with: to go on bit for bit, go on with kernels of
    /// the same numerics ([`KernelPath::available_equivalent`]).
    pub fn checkpoint_kernels(bytes: &[u8]) -> Result<KernelPath, RunCheckpointError> {
        let rest = bytes
            .strip_prefix(MAGIC)
            .ok_or(RunCheckpointError::NotACheckpoint)?;
        let (state, _) = split_blob(rest).ok_or(RunCheckpointError::Truncated("state"))?;
        #[derive(Deserialize)]
        struct Kernels {
            #[serde(default = "portable")]
            kernels: KernelPath,
        }
        let state: Kernels = serde_json::from_slice(state).map_err(RunCheckpointError::State)?;
        Ok(state.kernels)
    }

    /// The learner a checkpoint holds, with its run's config and the steps it had taken, read
    /// without resuming the run: to roll out the policy it had learnt (`dualrep sim
    /// --checkpoint`).
    pub fn checkpoint_learner(
        bytes: &[u8],
    ) -> Result<(EvaluativeRunConfig, Sac, u64), RunCheckpointError> {
        use RunCheckpointError as E;
        let Parts { state, learner, .. } = split_checkpoint(bytes)?;
        #[derive(Deserialize)]
        struct Head {
            config: EvaluativeRunConfig,
            steps: u64,
        }
        let head: Head = serde_json::from_slice(state).map_err(E::State)?;
        let learner = Sac::from_safetensors(learner).map_err(E::Learner)?;
        Ok((head.config, learner, head.steps))
    }

    /// The replay buffer a checkpoint holds (what its learner trains on), read without
    /// resuming the run: to see which answers a stopped session's learner had.
    pub fn checkpoint_replay(bytes: &[u8]) -> Result<ReplayBuffer, RunCheckpointError> {
        use RunCheckpointError as E;
        let Parts { state, rows, .. } = split_checkpoint(bytes)?;
        #[derive(Deserialize)]
        struct Replay {
            replay: ReplayLayout,
        }
        let state: Replay = serde_json::from_slice(state).map_err(E::State)?;
        ReplayBuffer::from_bytes(&state.replay, rows).map_err(E::Replay)
    }

    /// The run [`EvaluativeRun::checkpoint`] saved, with `trainer` put back to its state then,
    /// and the caller's notes. `config` must be the run's own: another run's is refused.
    pub fn resume(
        bytes: &[u8],
        config: &EvaluativeRunConfig,
        trainer: &mut dyn EvaluativeTrainer,
    ) -> Result<(Self, serde_json::Value), RunCheckpointError> {
        Self::resume_with_env(bytes, config, None, trainer)
    }

    /// [`EvaluativeRun::resume`] on `env` when given (an env in another process: connected
    /// again, it starts the checkpoint's episode from its reset seed), else on a new env of the
    /// config's task.
    pub fn resume_with_env(
        bytes: &[u8],
        config: &EvaluativeRunConfig,
        env: Option<Box<dyn crate::sim::Env>>,
        trainer: &mut dyn EvaluativeTrainer,
    ) -> Result<(Self, serde_json::Value), RunCheckpointError> {
        use RunCheckpointError as E;
        let Parts {
            state,
            learner,
            rows,
        } = split_checkpoint(bytes)?;
        let state: RunState = serde_json::from_slice(state).map_err(E::State)?;
        if (&state.config.task, state.config.scene_graph) != (&config.task, config.scene_graph) {
            return Err(E::OtherSceneGraph);
        }
        if state.config != *config {
            return Err(E::OtherConfig);
        }
        let learner = Sac::from_safetensors(learner).map_err(E::Learner)?;
        let replay = ReplayBuffer::from_bytes(&state.replay, rows).map_err(E::Replay)?;
        let schedule = state.schedule.restore().map_err(E::Rng)?;
        let episode_seeds: ChaCha8Rng = state.episode_seeds.restore().map_err(E::Rng)?;
        trainer.restore_state(&state.trainer).map_err(E::Trainer)?;

        let mut env = env.unwrap_or_else(|| state.config.make_env());
        let act_dim = env.spec().action_space.dim();
        let obs = env.try_reset(state.episode_seed).map_err(E::Reset)?;
        let run = Self {
            config: state.config,
            env,
            learner,
            replay,
            schedule,
            episode_seeds,
            episode_seed: state.episode_seed,
            obs,
            action: vec![0.0; act_dim],
            shown_action: vec![0.0; act_dim],
            steps: state.steps,
            episodes: state.episodes,
            episode_return: 0.0,
            episode_length: 0,
            cumulative_return: state.cumulative_return,
            successes: state.successes,
            mix_gate: state.mix_gate,
            feedback_count: state.feedback_count,
            no_feedback_count: state.no_feedback_count,
            held_back: state.held_back,
            queried: state.queried,
            taken_in: state.taken_in,
            pacing: state.pacing,
            next_episode_obs: None,
        };
        Ok((run, state.notes))
    }
}

/// A checkpoint's three parts.
struct Parts<'a> {
    /// The run's state, JSON.
    state: &'a [u8],
    /// The learner, safetensors.
    learner: &'a [u8],
    /// The replay rows.
    rows: &'a [u8],
}

fn split_checkpoint(bytes: &[u8]) -> Result<Parts<'_>, RunCheckpointError> {
    use RunCheckpointError as E;
    let rest = bytes.strip_prefix(MAGIC).ok_or(E::NotACheckpoint)?;
    let (state, rest) = split_blob(rest).ok_or(E::Truncated("state"))?;
    let (learner, rows) = split_blob(rest).ok_or(E::Truncated("learner"))?;
    Ok(Parts {
        state,
        learner,
        rows,
    })
}

/// A u64 LE length and that many bytes, then the rest.
fn split_blob(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    let (len, rest) = bytes.split_first_chunk::<8>()?;
    let len = usize::try_from(u64::from_le_bytes(*len)).ok()?;
    (rest.len() >= len).then(|| rest.split_at(len))
}

#[cfg(test)]
#[path = "run_checkpoint_tests.rs"]
mod tests;
