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
mod tests {
    use super::*;
    use crate::guidance::evaluative_run::EpisodeRecord;
    use crate::guidance::expert_oracle::ExpertOracle;
    use crate::sim::Task;

    fn tiny(task: Task, method: &str) -> EvaluativeRunConfig {
        let mut config = EvaluativeRunConfig::new(task, method.parse().unwrap(), 5);
        config.sac.hidden = vec![8, 8];
        config.sac.batch_size = 16;
        config
    }

    /// An oracle whose expert samples its actions, so its random stream matters.
    fn oracle(task: Task) -> ExpertOracle {
        let env = task.make_env();
        let spec = env.spec();
        let (obs_dim, act_dim) = (spec.observation_space.dim(), spec.action_space.dim());
        let mut config = crate::rl::SacConfig::for_task(task);
        config.hidden = vec![8, 8];
        ExpertOracle::new(Sac::new(obs_dim, act_dim, config, 11), act_dim)
    }

    fn drive(run: &mut EvaluativeRun, trainer: &mut ExpertOracle, to: u64) -> Vec<EpisodeRecord> {
        let mut episodes = Vec::new();
        while run.steps() < to {
            episodes.extend(run.step(trainer).episode);
        }
        episodes
    }

    /// A run of `config` driven past `to` steps to its next episode start, its trainer, and the
    /// checkpoint it saved there.
    fn saved_past(
        task: Task,
        config: &EvaluativeRunConfig,
        to: u64,
        budget: u64,
    ) -> (EvaluativeRun, ExpertOracle, Vec<u8>) {
        let mut trainer = oracle(task);
        let mut run = EvaluativeRun::new(config.clone(), budget);
        drive(&mut run, &mut trainer, to);
        while !run.at_episode_start() {
            run.step(&mut trainer);
        }
        let bytes = run.checkpoint(&trainer, serde_json::Value::Null);
        (run, trainer, bytes)
    }

    /// A faulty teacher (its own random stream) and a person's pace (its window of queries).
    fn faulty(task: Task, config: &EvaluativeRunConfig) -> ExpertOracle {
        oracle(task).with_faults(config.teacher, config.seed, 0.99)
    }

    #[test]
    fn a_resumed_run_continues_bit_for_bit_on_every_kernel_path() {
        for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
            kernels::with_path(path, || resumed_run_continues_bit_for_bit(path));
        }
    }

    fn resumed_run_continues_bit_for_bit(path: KernelPath) {
        let mut paced = tiny(Task::Placing, "dref");
        paced.teacher = crate::guidance::teacher::TeacherFaults {
            beta: Some(50.0),
            error: 0.2,
            ..Default::default()
        };
        paced.human_pace = Some(crate::guidance::human_pace::HumanPace {
            max_per_minute: 3,
            steps_per_minute: 40,
        });
        // The answered mix gated by the last episodes' outcomes, which the checkpoint keeps.
        let mut gated = tiny(Task::Placing, "dref");
        let critic = gated.sac.human_critic.as_mut().unwrap();
        (critic.mix, critic.failure_window) = (crate::rl::ActorMix::Answered, 3);
        // Tasks whose random episodes are short, so a few hundred steps cross several.
        for (task, method, config) in [
            (Task::Placing, "dref", tiny(Task::Placing, "dref")),
            (Task::Placing, "ef-50", tiny(Task::Placing, "ef-50")),
            (Task::LunarLander, "sac", tiny(Task::LunarLander, "sac")),
            (Task::Placing, "dref paced, faulty teacher", paced),
            (Task::Placing, "dref, answered mix gated by failures", gated),
        ] {
            let oracle = |task| faulty(task, &config);
            let steps = 600;
            let mut straight = EvaluativeRun::new(config.clone(), steps);
            let mut straight_oracle = oracle(task);
            let all = drive(&mut straight, &mut straight_oracle, steps);

            // Stop at the first episode start after step 200, checkpoint, and throw it all away.
            let mut first = EvaluativeRun::new(config.clone(), steps);
            let mut first_oracle = oracle(task);
            drive(&mut first, &mut first_oracle, 200);
            while !first.at_episode_start() {
                first.step(&mut first_oracle);
            }
            let stopped_at = first.steps();
            let successes_at_stop = first.successes();
            let gate_at_stop = first.mix_gate.clone();
            let bytes = first.checkpoint(&first_oracle, serde_json::json!({"note": stopped_at}));
            drop(first);
            assert_eq!(EvaluativeRun::checkpoint_kernels(&bytes).unwrap(), path);

            let mut fresh_oracle = oracle(task);
            let (mut resumed, notes) =
                EvaluativeRun::resume(&bytes, &config, &mut fresh_oracle).unwrap();
            assert_eq!(notes["note"], stopped_at);
            assert_eq!(resumed.steps(), stopped_at);
            assert_eq!(resumed.successes(), successes_at_stop);
            // The gate's window comes back as it was (for the gated run, with episodes in it).
            assert_eq!(resumed.mix_gate, gate_at_stop, "{task} {method}");
            if method.contains("gated") {
                assert_ne!(gate_at_stop, MixGate::default(), "episodes in the window");
            }
            let tail = drive(&mut resumed, &mut fresh_oracle, steps);
            let expected: Vec<_> = all
                .iter()
                .filter(|e| e.step > stopped_at)
                .cloned()
                .collect();
            assert!(
                !expected.is_empty(),
                "{task} {method}: episodes after the stop"
            );
            assert_eq!(tail, expected, "{path} {task} {method}");
            assert_eq!(
                resumed.learner().state_checksum(),
                straight.learner().state_checksum(),
                "{path} {task} {method}"
            );
            assert_eq!(resumed.feedback_count(), straight.feedback_count());
            assert_eq!(resumed.queries_held_back(), straight.queries_held_back());
            assert_eq!(resumed.cumulative_return(), straight.cumulative_return());
        }
    }

    #[test]
    fn a_run_is_the_same_bits_on_avx512_and_avx2_and_on_any_number_of_threads() {
        let fast: Vec<KernelPath> = [KernelPath::Avx512, KernelPath::Avx2]
            .into_iter()
            .filter(|p| p.is_available())
            .collect();
        let config = tiny(Task::Placing, "dref");
        let mut checksums = Vec::new();
        for &path in &fast {
            for threads in [1, 2] {
                let checksum = kernels::with_path(path, || {
                    kernels::with_threads(threads, || {
                        let mut run = EvaluativeRun::new(config.clone(), 300);
                        let mut trainer = oracle(Task::Placing);
                        drive(&mut run, &mut trainer, 300);
                        run.learner().state_checksum()
                    })
                });
                checksums.push((path, threads, checksum));
            }
        }
        for (path, threads, checksum) in &checksums {
            assert_eq!(*checksum, checksums[0].2, "{path} on {threads} threads");
        }
    }

    #[test]
    fn a_checkpoint_of_another_run_or_broken_bytes_is_refused() {
        let config = tiny(Task::Placing, "dref");
        let (_, mut trainer, bytes) = saved_past(Task::Placing, &config, 30, 100);
        let mut other = config.clone();
        other.seed += 1;
        let refused = |b: &[u8], c: &EvaluativeRunConfig, t: &mut ExpertOracle| {
            EvaluativeRun::resume(b, c, t)
                .err()
                .expect("refused")
                .to_string()
        };
        assert!(refused(&bytes, &other, &mut trainer).contains("another configuration"));
        // A remote env that comes back declaring another scene graph.
        let mut redeclared = config.clone();
        redeclared.scene_graph = crate::scene_graph::SceneGraph::Reaching;
        assert!(refused(&bytes, &redeclared, &mut trainer).contains("scene graph"));
        assert!(refused(&bytes[..bytes.len() - 4], &config, &mut trainer).contains("replay"));
        assert!(refused(&bytes[..40], &config, &mut trainer).contains("truncated"));
        assert!(refused(b"hello", &config, &mut trainer).contains("not a dualrep"));
        assert!(EvaluativeRun::resume(&bytes, &config, &mut trainer).is_ok());
    }

    #[test]
    fn a_checkpoints_learner_acts_as_the_run_that_saved_it() {
        let config = tiny(Task::LunarLander, "ef-100");
        let (run, _, bytes) = saved_past(Task::LunarLander, &config, 300, 400);
        let (read, mut learner, steps) = EvaluativeRun::checkpoint_learner(&bytes).unwrap();
        assert_eq!((read, steps), (config, run.steps()));
        assert!(learner.updates() > 0, "a learner that has trained");
        let mut saved = run.into_learner();
        let (mut ours, mut theirs) = ([0.0f32; 2], [0.0f32; 2]);
        for i in 0..20 {
            let obs: Vec<f32> = (0..8).map(|j| ((i * 8 + j) as f32 * 0.37).sin()).collect();
            learner.act(&obs, i % 2 == 0, &mut ours);
            saved.act(&obs, i % 2 == 0, &mut theirs);
            assert_eq!(
                ours, theirs,
                "observation {i}: the same action, sampled or not"
            );
        }
        assert!(EvaluativeRun::checkpoint_learner(&bytes[..40]).is_err());
        assert!(EvaluativeRun::checkpoint_learner(b"hello").is_err());
    }
}
