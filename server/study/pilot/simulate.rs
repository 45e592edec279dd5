//! Training the pool: each simulated participant's session in each condition, run headless
//! with the synthetic teacher, on `jobs` threads at once (each run on one thread, its learner
//! too), and scored as the study would score a person's session.
//!
//! The score is Figure 4's measure for evaluative methods (the cumulative reward over the
//! session, with the share of steps that asked for feedback beside it) and Figure 6's for
//! preference methods (the reward's alignment after the last query; every query is feedback,
//! so no share).

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};

use serde::Serialize;

use crate::guidance::drpl::run::{PreferenceRun, PreferenceRunConfig};
use crate::guidance::drpl::simulated_teacher::SimulatedTeacher;
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::{EvaluativeTrainer, NoTrainer};
use crate::guidance::expert_oracle::ExpertOracle;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::Sac;
use crate::rl::kernels;
use crate::session::plan::RunConfig;
use crate::sim::{Task, TaskRef};

/// One session of the pool: a participant in a condition, its configuration read and checked.
#[derive(Clone, Debug)]
pub struct PilotRun {
    pub participant: usize,
    /// The condition's index in the study.
    pub condition: usize,
    /// Where the condition falls in the participant's order (0: first).
    pub position: usize,
    pub seed: u64,
    /// Environment steps or queries.
    pub budget: u64,
    pub config: RunConfig,
}

/// What one session scored.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Score {
    /// The cumulative reward (evaluative) or the final alignment (preference).
    pub score: f64,
    /// Queries asked: steps with feedback (evaluative), or preference queries.
    pub feedback_count: u64,
    /// Percent of steps that asked for feedback; `None` for preference methods.
    pub feedback_percent: Option<f64>,
    /// Finished episodes (evaluative) or recorded trajectories (preference).
    pub episodes: u64,
}

/// The experts the synthetic evaluative teacher consults, by task.
pub type Experts = Vec<(Task, Sac)>;

/// The tasks whose expert the runs need (DREF and EF conditions).
pub fn tasks_needing_experts(runs: &[PilotRun]) -> Vec<Task> {
    let mut tasks: Vec<Task> = runs
        .iter()
        .filter_map(|r| match &r.config {
            RunConfig::Evaluative(c) if c.method != EvaluativeMethod::Sac => match c.task {
                TaskRef::Builtin(t) => Some(t),
                TaskRef::Declared(_) => None,
            },
            _ => None,
        })
        .collect();
    tasks.sort();
    tasks.dedup();
    tasks
}

/// Runs every session, `jobs` at a time, and returns their scores in the order of `runs`;
/// `on_done` hears of each as it ends (from the thread that ran it).
pub fn run_all(
    runs: &[PilotRun],
    experts: &Experts,
    jobs: usize,
    on_done: &(dyn Fn(&PilotRun, &Result<Score, String>) + Sync),
) -> Vec<Result<Score, String>> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<Score, String>>>> = Mutex::new(vec![None; runs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, runs.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, AtomicOrdering::Relaxed);
                    let Some(run) = runs.get(i) else { break };
                    let result = kernels::with_threads(1, || run_one(run, experts));
                    on_done(run, &result);
                    results.lock().expect("no run panics holding the lock")[i] = Some(result);
                }
            });
        }
    });
    results
        .into_inner()
        .expect("no run panics holding the lock")
        .into_iter()
        .map(|r| r.expect("every run ran"))
        .collect()
}

/// One session, headless, with the synthetic teacher.
pub fn run_one(run: &PilotRun, experts: &Experts) -> Result<Score, String> {
    match &run.config {
        RunConfig::Evaluative(config) => evaluative((**config).clone(), run.budget, experts),
        RunConfig::Preference(config) => Ok(preference((**config).clone(), run.budget)),
    }
}

fn evaluative(config: EvaluativeRunConfig, steps: u64, experts: &Experts) -> Result<Score, String> {
    // The teacher a synthetic session has (`session::evaluative_loop`): the task's expert,
    // the authors' rule, the participant's faults.
    let mut teacher: Box<dyn EvaluativeTrainer> = match config.method {
        EvaluativeMethod::Sac => Box::new(NoTrainer),
        _ => {
            let task = match config.task {
                TaskRef::Builtin(t) => t,
                TaskRef::Declared(_) => return Err("a pilot runs on our own tasks only".into()),
            };
            let expert = experts
                .iter()
                .find(|(t, _)| *t == task)
                .map(|(_, e)| e.clone())
                .ok_or_else(|| format!("no expert for {task}"))?;
            let act_dim = config.make_env().spec().action_space.dim();
            Box::new(
                ExpertOracle::new(expert, act_dim)
                    .with_config(config.oracle)
                    .with_faults(config.teacher, config.seed, f64::from(config.sac.gamma)),
            )
        }
    };
    let mut run = EvaluativeRun::new(config, steps);
    while run.steps() < steps {
        run.step(teacher.as_mut());
    }
    Ok(Score {
        score: run.cumulative_return(),
        feedback_count: run.feedback_count(),
        feedback_percent: Some(100.0 * run.feedback_count() as f64 / run.steps() as f64),
        episodes: run.episodes(),
    })
}

fn preference(config: PreferenceRunConfig, queries: u64) -> Score {
    let mut run = PreferenceRun::new(config);
    let mut teacher = SimulatedTeacher::new(
        run.theta_true().to_vec(),
        run.config().teacher,
        run.teacher_seed(),
        run.pool(),
    );
    while (run.queries() as u64) < queries {
        if run.step(&mut teacher).is_none() {
            // No new pair left: the session ends early, as a person's would.
            break;
        }
    }
    Score {
        score: run.alignment(),
        feedback_count: run.queries() as u64,
        feedback_percent: None,
        episodes: run.pool().trajectories() as u64,
    }
}
