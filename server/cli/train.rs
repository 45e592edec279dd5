//! `dualrep train`: one SAC / EF-p% / DREF run with the synthetic evaluative trainer, writing
//! `metrics.csv` (a row per finished episode, flushed as it happens) and `summary.json` (written
//! last, atomically: its presence marks a finished run for `reproduce`).
//!
//! A long run also keeps `checkpoint.run` (every `--checkpoint-every` steps, at the next
//! episode's start): a run stopped midway and started again with the same arguments goes on
//! from there, bit for bit, and the file is removed once `summary.json` is written (the
//! checkpoint, the folder's lock and what a resume keeps: `train_checkpoint.rs`).
//! `--keep-checkpoints` also keeps each one under `checkpoints/` by its step, past the run's end.
//! `--branch-from` begins a run as another run's checkpoint (`train_branch.rs`).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use super::answer_log::{AnswerLog, keep_answer_rows};
use super::episode_file::EpisodeFile;
use super::learner_log::{LearnerLog, keep_learner_rows};
use super::output::publish_summary;
use super::overrides;
use super::progress::Progress;
use super::remote::RemoteArgs;
use super::train_branch::{BranchedFrom, branch_checkpoint, start_branch};
pub use super::train_checkpoint::CHECKPOINT_FILE;
use super::train_checkpoint::{
    Checkpointer, KEPT_CHECKPOINTS_DIR, RECENT_EPISODES, ResumeNotes, keep_episodes,
    keep_kernels_of, lock_run_dir,
};
use crate::guidance::evaluative_run::{EpisodeRecord, EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::EvaluativeTrainer;
pub use crate::guidance::evaluative_trainer::NoTrainer;
use crate::guidance::expert_oracle::ExpertOracle;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::remote_env::RemoteEnv;
use crate::rl::Sac;
use crate::rl::kernels::{self, KernelPath};
use crate::sim::{Env, Task};

#[derive(Debug, Args)]
pub struct TrainArgs {
    /// reaching, placing or lunar-lander (with `--env-url`: the task the remote env copies).
    #[arg(long)]
    pub task: Option<Task>,
    /// sac, dref or ef-<percent> (ef-100, ef-50, ef-25, ef-6.2, ...).
    #[arg(long)]
    pub method: EvaluativeMethod,
    /// Environment steps (one gradient step each).
    #[arg(long, default_value_t = 100_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub steps: u64,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub overrides: overrides::OverrideArgs,
    /// The expert the synthetic trainer consults [default: models/<task>.safetensors if there
    /// is one in the current directory, else the one inside the binary].
    #[arg(long)]
    pub expert: Option<PathBuf>,
    /// Save the whole run to OUT/checkpoint.run about every N steps (0: never), so a stopped
    /// run resumes instead of starting over.
    #[arg(long, default_value_t = 10_000)]
    pub checkpoint_every: u64,
    /// Also keep each checkpoint as OUT/checkpoints/step-<N>.run (N: the step it was taken at),
    /// where the run's end leaves it: a finished run's policy and query rule at those steps,
    /// for `sim --checkpoint` and `graph_outcomes.py --rule-from`. About the size of
    /// `checkpoint.run` each.
    #[arg(long)]
    pub keep_checkpoints: bool,
    /// Begin as another run's checkpoint (one `--keep-checkpoints` kept, or a
    /// `checkpoint.run`; given a folder of kept ones or a run's folder, the latest at or before
    /// this command's `feedback_until`) instead of from step 0: that run to its step, this
    /// command's settings after. They may differ from that run's only in `feedback_until`, and
    /// only where it has not acted yet (a cut at or after the checkpoint's step); anything else
    /// is refused by name. The run's rows up to the checkpoint are copied from its folder into
    /// OUT. Once OUT holds a checkpoint of its own, the run resumes from that instead.
    #[arg(long, value_name = "CHECKPOINT")]
    pub branch_from: Option<PathBuf>,
    #[command(flatten)]
    pub remote: RemoteArgs,
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct TrainSummary {
    /// The task's name (a declared task's: its env's id).
    pub task: String,
    /// The remote env the run stepped, if not our simulator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env_url: Option<String>,
    pub method: EvaluativeMethod,
    pub seed: u64,
    pub steps: u64,
    pub episodes: u64,
    pub cumulative_return: f64,
    pub feedback_count: u64,
    pub feedback_fraction: f64,
    /// Queries the method wanted that a person's pace (`max_queries_per_minute`) held back.
    pub queries_held_back: u64,
    /// The longest stretch of consecutive asked steps, over the run and from step 2,000 on.
    pub longest_flood: u64,
    pub longest_flood_after_2k: u64,
    /// Mean return of the last 10 finished episodes.
    pub final_mean_return: f64,
    /// Success rate of the last 10 finished episodes.
    pub final_success_rate: f64,
    pub wall_seconds: f64,
    pub updates_per_second: f64,
    /// The kernels that computed the run (`portable`, or `avx2` / `avx512`, which give the same
    /// bits), and the most threads one product used.
    pub kernels: KernelPath,
    pub threads: usize,
    /// The checkpoint of another run this one began as (`--branch-from`), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub branched_from: Option<BranchedFrom>,
    pub config: EvaluativeRunConfig,
}

/// The run's config: defaults for task and method, then the TOML file, then `--set`.
pub fn resolve_config(
    task: Task,
    method: EvaluativeMethod,
    seed: u64,
    args: &overrides::OverrideArgs,
) -> anyhow::Result<EvaluativeRunConfig> {
    args.settings()?
        .evaluative(task, method, seed)
        .map_err(anyhow::Error::msg)
}

/// Load an expert written by `dualrep expert`.
pub fn load_expert(path: &Path, task: &str) -> anyhow::Result<Sac> {
    Ok(crate::session::load_expert(path, task)?)
}

/// The run's config on a remote env: `task`'s (the env stands in for it), or the defaults for
/// the task the env declared; then the TOML file and `--set`.
pub fn resolve_remote_config(
    env: &RemoteEnv,
    task: Option<Task>,
    method: EvaluativeMethod,
    seed: u64,
    args: &overrides::OverrideArgs,
) -> anyhow::Result<EvaluativeRunConfig> {
    match task {
        Some(task) => resolve_config(task, method, seed, args),
        None => {
            let d = env.description();
            let defaults = EvaluativeRunConfig::declared(d.declared_task(), d.graph, method, seed);
            args.settings()?
                .apply_evaluative(defaults)
                .map_err(anyhow::Error::msg)
        }
    }
}

/// The expert the synthetic trainer consults: `--expert`, else `models/<task>.safetensors` in
/// the current directory, else (for our tasks) the one inside the binary.
fn find_expert(explicit: Option<&Path>, task: &str, builtin: Option<Task>) -> anyhow::Result<Sac> {
    let local = PathBuf::from(format!("models/{task}.safetensors"));
    match (explicit, builtin) {
        (Some(path), _) => load_expert(path, task),
        (None, _) if local.is_file() => load_expert(&local, task),
        (None, Some(t)) => Ok(crate::session::load_task_expert(None, t)?),
        (None, None) => anyhow::bail!(
            "{task} has no shipped expert: train one with `dualrep expert --env-url ... --out {}` or give --expert",
            local.display()
        ),
    }
}

/// `metrics.csv`'s columns: one row per finished episode.
const METRICS_HEADER: &str = "step,episode,return,length,outcome,cumulative_return,feedback_count,\
     feedback_fraction,states_with_feedback,steps_since_query,longest_flood";

/// Run `run` to `steps`, writing finished episodes to `metrics.csv`, the learner's means over
/// each to `learner.csv` and the answers in each by sign to `answers.csv` in `out` (new files,
/// or appended to those an earlier call began when `append`).
pub fn drive(
    run: &mut EvaluativeRun,
    trainer: &mut dyn EvaluativeTrainer,
    steps: u64,
    out: &Path,
    label: &str,
    append: bool,
    mut checkpoints: Option<&mut Checkpointer>,
) -> anyhow::Result<Vec<EpisodeRecord>> {
    let mut metrics = EpisodeFile::open(&out.join("metrics.csv"), METRICS_HEADER, append)?;
    let mut learner_log = LearnerLog::open(out, append)?;
    let mut answer_log = AnswerLog::open(out, append)?;
    let mut episodes = Vec::new();
    let mut progress = Progress::new(steps, label);
    while run.steps() < steps {
        let report = run
            .try_step(trainer)
            .with_context(|| format!("{label}: at step {}", run.steps()))?;
        if let Some(stats) = &report.update {
            learner_log.update(stats);
        }
        if let Some(answer) = report.evaluation {
            answer_log.answered(answer);
        }
        if let Some(e) = report.episode {
            learner_log.episode_end(e.step, e.episode)?;
            answer_log.episode_end(e.step, e.episode)?;
            metrics.row(format_args!(
                "{},{},{},{},{},{},{},{},{},{},{}",
                e.step,
                e.episode,
                e.episode_return,
                e.length,
                e.outcome.id(),
                e.cumulative_return,
                e.feedback_count,
                e.feedback_fraction,
                e.states_with_feedback,
                e.steps_since_query,
                e.longest_flood
            ))?;
            if let Some(c) = checkpoints.as_deref_mut() {
                c.record(&e);
                c.maybe_save(run, trainer)?;
            }
            episodes.push(e);
        }
        progress.update(run.steps(), || {
            format!(
                "episodes {} cumulative {:.0} feedback {}",
                run.episodes(),
                run.cumulative_return(),
                run.feedback_count()
            )
        });
    }
    progress.finish();
    Ok(episodes)
}

/// Mean return and success rate of the last `n` episodes (0 if none finished).
pub fn final_performance(episodes: &[EpisodeRecord], n: usize) -> (f64, f64) {
    let tail = &episodes[episodes.len().saturating_sub(n)..];
    if tail.is_empty() {
        return (0.0, 0.0);
    }
    let mean = tail.iter().map(|e| e.episode_return).sum::<f64>() / tail.len() as f64;
    let successes = tail
        .iter()
        .filter(|e| e.outcome == crate::sim::Outcome::Success)
        .count();
    (mean, successes as f64 / tail.len() as f64)
}

/// Where a run begins: its own checkpoint, another run's (`--branch-from`), or step 0.
enum Start {
    Resume(Vec<u8>),
    Branch { from: PathBuf, bytes: Vec<u8> },
    New,
}

impl Start {
    /// The run's own checkpoint first (a branch that has begun goes on from its own), then the
    /// one `--branch-from` names, else step 0.
    fn choose(
        own: &Path,
        branch_from: Option<&Path>,
        config: &EvaluativeRunConfig,
    ) -> anyhow::Result<Self> {
        match fs::read(own) {
            Ok(bytes) => Ok(Self::Resume(bytes)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => match branch_from {
                Some(given) => {
                    let from = branch_checkpoint(given, config)?;
                    let bytes =
                        fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
                    Ok(Self::Branch { from, bytes })
                }
                None => Ok(Self::New),
            },
            Err(e) => Err(e).with_context(|| format!("reading {}", own.display())),
        }
    }
}

pub fn run(args: TrainArgs) -> anyhow::Result<()> {
    let remote = args.remote.connect(args.task)?;
    let config = match (&remote, args.task) {
        (Some(env), task) => {
            resolve_remote_config(env, task, args.method, args.seed, &args.overrides)?
        }
        (None, Some(task)) => resolve_config(task, args.method, args.seed, &args.overrides)?,
        (None, None) => unreachable!("RemoteArgs::connect asks for a task"),
    };
    let task_id = config.task.id().to_string();
    let mut trainer: Box<dyn EvaluativeTrainer> = match args.method {
        EvaluativeMethod::Sac => Box::new(NoTrainer),
        _ => {
            let expert = find_expert(args.expert.as_deref(), &task_id, args.task)?;
            let act_dim = match &remote {
                Some(env) => env.spec().action_space.dim(),
                None => config.make_env().spec().action_space.dim(),
            };
            Box::new(
                ExpertOracle::new(expert, act_dim)
                    .with_config(config.oracle)
                    .with_faults(config.teacher, config.seed, f64::from(config.sac.gamma)),
            )
        }
    };
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let _only_writer = lock_run_dir(&args.out)?;

    let label = format!("{task_id} {} seed {}", args.method, args.seed);
    let checkpoint_path = args.out.join(CHECKPOINT_FILE);
    let start = Start::choose(&checkpoint_path, args.branch_from.as_deref(), &config)?;
    match &start {
        Start::Resume(bytes) => keep_kernels_of(bytes, &checkpoint_path, &label)?,
        Start::Branch { from, bytes } => keep_kernels_of(bytes, from, &label)?,
        Start::New => {}
    }
    eprintln!(
        "{label}: {} kernels, {} thread(s)",
        kernels::current_path(),
        kernels::threads_now()
    );
    let remote_env = remote.map(|env| Box::new(env) as Box<dyn Env>);
    let (mut run, notes) = match start {
        Start::Resume(bytes) => {
            let (run, notes) =
                EvaluativeRun::resume_with_env(&bytes, &config, remote_env, trainer.as_mut())
                    .with_context(|| {
                        format!(
                            "resuming from {} (delete it to start the run over)",
                            checkpoint_path.display()
                        )
                    })?;
            let notes: ResumeNotes = serde_json::from_value(notes)
                .with_context(|| format!("reading the notes in {}", checkpoint_path.display()))?;
            keep_episodes(&args.out.join("metrics.csv"), run.episodes())?;
            keep_learner_rows(&args.out, run.episodes())?;
            keep_answer_rows(&args.out, run.episodes())?;
            eprintln!(
                "{label}: resumed from {CHECKPOINT_FILE} at step {}",
                run.steps()
            );
            (run, notes)
        }
        Start::Branch { from, bytes } => {
            let (run, notes) = start_branch(
                &from,
                &bytes,
                &config,
                args.steps,
                remote_env,
                trainer.as_mut(),
                &args.out,
            )?;
            eprintln!(
                "{label}: branched from {} at step {}",
                from.display(),
                run.steps()
            );
            (run, notes)
        }
        Start::New => {
            let run = match remote_env {
                Some(env) => EvaluativeRun::with_env(config.clone(), env, args.steps)?,
                None => EvaluativeRun::new(config.clone(), args.steps),
            };
            (run, ResumeNotes::default())
        }
    };
    // Written once the run could begin: a branch refused leaves the folder as it was.
    fs::write(
        args.out.join("config.json"),
        serde_json::to_vec_pretty(&config)?,
    )?;
    let resumed = run.steps() > 0;
    let keep_in = args
        .keep_checkpoints
        .then(|| args.out.join(KEPT_CHECKPOINTS_DIR));
    let mut checkpointer = Checkpointer::new(
        checkpoint_path.clone(),
        args.checkpoint_every,
        keep_in,
        &run,
        notes,
    );
    drive(
        &mut run,
        trainer.as_mut(),
        args.steps,
        &args.out,
        &label,
        resumed,
        Some(&mut checkpointer),
    )?;
    let wall_seconds = checkpointer.wall_seconds();
    let (final_mean_return, final_success_rate) =
        final_performance(checkpointer.recent_episodes(), RECENT_EPISODES);
    let summary = TrainSummary {
        task: task_id,
        env_url: args.remote.env_url.clone(),
        method: args.method,
        seed: args.seed,
        steps: run.steps(),
        episodes: run.episodes(),
        cumulative_return: run.cumulative_return(),
        feedback_count: run.feedback_count(),
        feedback_fraction: run.feedback_count() as f64 / run.steps() as f64,
        queries_held_back: run.queries_held_back(),
        longest_flood: run.pacing().longest_flood,
        longest_flood_after_2k: run.pacing().longest_flood_settled,
        final_mean_return,
        final_success_rate,
        wall_seconds,
        updates_per_second: run.learner().updates() as f64 / wall_seconds,
        kernels: kernels::current_path(),
        threads: kernels::threads_now(),
        branched_from: checkpointer.branched_from().cloned(),
        config,
    };
    publish_summary(&args.out.join("summary.json"), &summary)?;
    match fs::remove_file(&checkpoint_path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", checkpoint_path.display()))
        }
        _ => Ok(()),
    }
}
