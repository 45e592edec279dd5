//! `dualrep sim`: episodes of a random or heuristic policy, or of the policy a `train` run's
//! checkpoint had learnt, summarised as one JSON object, and optionally every step of them as
//! CSV with the scene graph's abstract state (and, `--judge`, the run's H_hat beside its
//! teacher's answer: `sim_judge.rs`).

use std::fs::{self, File};
use std::io::{self, BufWriter, Write as _};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;

use super::overrides::parse_pair;
use super::sim_judge::{Judge, refit_critic};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::Evaluation;
use crate::rl::Sac;
use crate::rl::sac::Refit;
use crate::scene_graph::SceneGraph;
use crate::settings::Settings;
use crate::sim::rollout::{ActionNoise, Actor, SimplePolicy, StepSeen, run_episodes_watched};
use crate::sim::{Task, TaskRef};

#[derive(Debug, Args)]
pub struct SimArgs {
    /// reaching, placing or lunar-lander (with --checkpoint: the run's, if given).
    #[arg(long, required_unless_present = "checkpoint")]
    pub task: Option<Task>,
    /// random or heuristic.
    #[arg(long, default_value = "heuristic")]
    pub policy: SimplePolicy,
    /// Act with the policy a `train` run had learnt: its `checkpoint.run` (a running or stopped
    /// run's) or one it kept (`train --keep-checkpoints`), sampled as in training; the env's
    /// version and the scene graph are the run's.
    #[arg(long, value_name = "PATH", conflicts_with_all = ["policy", "options"])]
    pub checkpoint: Option<PathBuf>,
    /// With --checkpoint: act with the mean action (tanh of the mean) instead of sampling.
    #[arg(long, requires = "checkpoint")]
    pub deterministic: bool,
    /// With --checkpoint: beside each step, the run's human critic H_hat(s, a) and the answer its
    /// synthetic teacher (the task's shipped expert as the run's oracle, without faults, at the
    /// checkpoint's step) would give there. The summary says how well the one stands in for the
    /// other (`judge`); `--steps` gains the columns `h_hat` and `answer` (+1, 0, -1).
    #[arg(long, requires = "checkpoint")]
    pub judge: bool,
    /// With --judge: the human critic of another checkpoint of the same task, on the steps of
    /// --checkpoint's policy and beside the same teacher (--checkpoint's run's, at its step):
    /// two runs' critics on the same steps.
    #[arg(long, value_name = "PATH", requires = "judge")]
    pub critic_from: Option<PathBuf>,
    /// With --judge: also K actions around each step's (Gaussian, sd 0.3, clipped), ranked by
    /// the critic's H_hat and by the teacher's expert's Q; the summary's
    /// `within_state_rank_correlation` is their mean Spearman's rho over the steps (0: off).
    #[arg(long, value_name = "K", default_value_t = 0, requires = "judge")]
    pub judge_actions: usize,
    /// With --judge: judge instead a human critic fitted again from fresh heads for N gradient
    /// steps (the run's batch size and learning rate) on the answered transitions of the
    /// critic's checkpoint's replay alone: what those answers teach apart from the run that
    /// asked them.
    #[arg(long, value_name = "N", requires = "judge", value_parser = clap::value_parser!(u64).range(1..))]
    pub refit_critic: Option<u64>,
    /// With --refit-critic: only the replay's first K answered transitions (by time).
    #[arg(long, value_name = "K", requires = "refit_critic")]
    pub refit_answers: Option<usize>,
    /// With --refit-critic: the seed of the fresh heads and of their batches.
    #[arg(
        long,
        value_name = "SEED",
        default_value_t = 0,
        requires = "refit_critic"
    )]
    pub refit_seed: u64,
    /// Number of episodes (seeds seed, seed + 1, ...).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub episodes: u32,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The standard deviation of Gaussian noise added to each of the policy's actions (then
    /// clipped to [-1, 1]): a heuristic that sometimes fails.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f32,
    /// The noise's correlation from one step to the next, in [0, 1): 0 is white noise, 0.95
    /// keeps a push for about 20 steps (0.4 s on Lunar Lander).
    #[arg(long, default_value_t = 0.0)]
    pub noise_correlation: f32,
    /// Write every step here as CSV: seed, t, the observation after the step, the action, the
    /// reward, the scene graph on them (the product's, or the checkpoint's run's; its abstract
    /// state as bits, predicate order) and, on an episode's last step, its outcome.
    #[arg(long, value_name = "PATH")]
    pub steps: Option<PathBuf>,
    /// Choose the task's version: `--set variant=uniform`, `--set release_at=0.9`,
    /// `--set success=through`, `--set observe_grip=level` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pub options: Vec<(String, String)>,
}

pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let noise = ActionNoise {
        std: args.noise,
        correlation: args.noise_correlation,
    }
    .check()
    .context("--noise, --noise-correlation")?;
    let mut judge = None;
    let (task, options, graph, mut learned) = match &args.checkpoint {
        None => {
            let task = args
                .task
                .expect("clap requires --task without --checkpoint");
            let options =
                Settings::from_pairs(args.options.iter().map(|(k, v)| (k.as_str(), v.as_str())))
                    .and_then(|s| s.env_options(task))?;
            (task, options, SceneGraph::for_task(task), None)
        }
        Some(path) => {
            let bytes =
                fs::read(path).with_context(|| format!("--checkpoint {}", path.display()))?;
            let (task, config, learner, step) = checkpoint_policy(&bytes, path, args.task)?;
            eprintln!("sim: the policy of {} after {step} steps", path.display());
            if args.judge {
                // The critic is the learner's own (or --critic-from's), apart from the copy
                // that acts; the teacher is this run's, at its step.
                let other_bytes;
                let (mut critic, critic_bytes) = match &args.critic_from {
                    None => (learner.clone(), &bytes),
                    Some(other) => {
                        other_bytes = fs::read(other)
                            .with_context(|| format!("--critic-from {}", other.display()))?;
                        let (_, _, critic, at) =
                            checkpoint_policy(&other_bytes, other, Some(task))?;
                        eprintln!(
                            "sim: judged by the critic of {} after {at} steps",
                            other.display()
                        );
                        (critic, &other_bytes)
                    }
                };
                let refit = match args.refit_critic {
                    None => None,
                    Some(updates) => Some(refit_critic(
                        &mut critic,
                        critic_bytes,
                        Refit {
                            updates,
                            answers: args.refit_answers,
                            seed: args.refit_seed,
                        },
                    )?),
                };
                let expert = crate::session::load_task_expert(None, task)?;
                let act_dim = config.make_env().spec().action_space.dim();
                let mut judged =
                    Judge::new(&config, critic, expert.clone(), step, act_dim)?.with_refit(refit);
                if args.judge_actions > 0 {
                    judged = judged.with_actions_around(expert, args.judge_actions, args.seed);
                }
                judge = Some(judged);
            }
            (task, config.env, config.scene_graph, Some(learner))
        }
    };
    // Opened before the episodes run, so that a path that cannot be written is said at once.
    let mut steps = match &args.steps {
        None => None,
        Some(path) => Some(
            StepTable::create(path, graph, judge.is_some())
                .with_context(|| format!("--steps {}", path.display()))?,
        ),
    };
    let mut watch = |seen: StepSeen<'_>| {
        let judged = judge.as_mut().map(|j| j.judge(&seen));
        if let Some(table) = steps.as_mut() {
            table.push(&seen, judged);
        }
    };
    let deterministic = args.deterministic;
    let mut act;
    let mut actor = match learned.as_mut() {
        None => Actor::Simple(args.policy),
        Some(learner) => {
            act = |obs: &[f32], action: &mut [f32]| learner.act(obs, deterministic, action);
            Actor::Learned(&mut act)
        }
    };
    let (summary, _) = run_episodes_watched(
        task,
        &options,
        &mut actor,
        noise,
        args.episodes,
        args.seed,
        &mut watch,
    );
    if let (Some(path), Some(table)) = (&args.steps, steps) {
        table
            .finish(path)
            .with_context(|| format!("--steps {}", path.display()))?;
    }
    let mut summary = serde_json::to_value(&summary)?;
    if let Some(judge) = &judge {
        summary["judge"] = serde_json::to_value(judge.summary())?;
    }
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

/// The task, config, learner and step of the `train` run's checkpoint `bytes` (read from
/// `path`); `task`, if given, must be the run's.
fn checkpoint_policy(
    bytes: &[u8],
    path: &Path,
    task: Option<Task>,
) -> anyhow::Result<(Task, EvaluativeRunConfig, Sac, u64)> {
    let (config, learner, steps) = EvaluativeRun::checkpoint_learner(bytes)
        .with_context(|| format!("--checkpoint {}", path.display()))?;
    let TaskRef::Builtin(run_task) = config.task else {
        bail!(
            "--checkpoint {}: its run's env lived in another process; sim runs our tasks only",
            path.display()
        );
    };
    if let Some(asked) = task.filter(|t| *t != run_task) {
        bail!(
            "--task {asked}: the checkpoint {} is of a {run_task} run",
            path.display()
        );
    }
    Ok((run_task, config, learner, steps))
}

/// The steps of `sim --steps`, one CSV row each, written as the episodes run into
/// `<path>.partial`, which becomes `path` when they have all run: the file appears whole or not
/// at all, and thousands of episodes take no more memory than one.
struct StepTable {
    graph: SceneGraph,
    /// Whether each row ends with the judge's `h_hat` and `answer`.
    judged: bool,
    partial: PathBuf,
    out: BufWriter<File>,
    /// The header is written on the first step, when the observation's and action's sizes are
    /// known.
    header_written: bool,
    /// The first write that failed: the episodes run on (a watcher cannot stop them), and
    /// [`StepTable::finish`] reports it.
    failed: Option<io::Error>,
}

impl StepTable {
    fn create(path: &Path, graph: SceneGraph, judged: bool) -> anyhow::Result<Self> {
        let partial = path.with_extension("partial");
        let file =
            File::create(&partial).with_context(|| format!("creating {}", partial.display()))?;
        Ok(Self {
            graph,
            judged,
            partial,
            out: BufWriter::new(file),
            header_written: false,
            failed: None,
        })
    }

    fn push(&mut self, seen: &StepSeen<'_>, judged: Option<(f32, Evaluation)>) {
        if self.failed.is_none()
            && let Err(e) = self.write_row(seen, judged)
        {
            self.failed = Some(e);
        }
    }

    fn write_row(
        &mut self,
        seen: &StepSeen<'_>,
        judged: Option<(f32, Evaluation)>,
    ) -> io::Result<()> {
        let out = &mut self.out;
        if !self.header_written {
            out.write_all(b"seed,t")?;
            for i in 0..seen.next_obs.len() {
                write!(out, ",obs_{i}")?;
            }
            for i in 0..seen.action.len() {
                write!(out, ",action_{i}")?;
            }
            out.write_all(b",reward,abstract_state,outcome")?;
            out.write_all(if self.judged {
                b",h_hat,answer\n"
            } else {
                b"\n"
            })?;
            self.header_written = true;
        }
        write!(out, "{},{}", seen.seed, seen.t)?;
        for v in seen.next_obs.iter().chain(seen.action) {
            write!(out, ",{v}")?;
        }
        let state = self.graph.evaluate(seen.next_obs, seen.action);
        write!(
            out,
            ",{},{},{}",
            seen.reward,
            state.to_bit_string(self.graph.dim()),
            seen.outcome.map_or("", |o| o.id())
        )?;
        match judged {
            Some((h_hat, answer)) => writeln!(out, ",{h_hat},{}", answer.value()),
            None => writeln!(out),
        }
    }

    /// Flushes the rows and puts the file in place; on a failed write, removes the partial file
    /// and says what failed.
    fn finish(self, path: &Path) -> anyhow::Result<()> {
        let written = match self.failed {
            Some(e) => Err(e),
            None => self
                .out
                .into_inner()
                .map_err(io::IntoInnerError::into_error)
                .and_then(|file| file.sync_all()),
        };
        if let Err(e) = written {
            let _ = fs::remove_file(&self.partial);
            return Err(e).with_context(|| format!("writing {}", self.partial.display()));
        }
        fs::rename(&self.partial, path)
            .with_context(|| format!("renaming {} to {}", self.partial.display(), path.display()))
    }
}
