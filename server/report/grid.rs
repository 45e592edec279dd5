//! The experiment grid of a figure, pure: which runs, where their files go, and the exact
//! `dualrep train` / `dualrep prefs` command line of each.

use std::path::PathBuf;

use super::methods::{matched_ef_method, paper_steps};
use super::run_files::run_dir;
use crate::sim::Task;

/// Why a grid (Figure 3's or 5's, or the robustness grid) cannot run, found before any run
/// starts.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("a grid needs at least one task, one seed and one method")]
    Empty,
    /// The robustness figure asked of a `GridConfig`.
    #[error("the robustness grid is a `report::robustness::RobustnessConfig`")]
    RobustnessFigure,
    /// A method `train` or `prefs` does not run for the figure.
    #[error("unknown method {method:?} for {}: expected {}", .figure.stem(), .figure.known_methods())]
    UnknownMethod { method: String, figure: Figure },
    /// A robustness grid without tasks or seeds.
    #[error("a grid needs at least one task and one seed")]
    NoTaskOrSeed,
    /// A robustness grid without methods.
    #[error("a robustness grid needs an evaluative or a preference method")]
    NoMethod,
    /// An error rate (percent) of 100 or more.
    #[error("--errors: {0} is not a percentage below 100")]
    ErrorRate(u32),
    /// A rationality that is negative or not finite.
    #[error("--betas: {0} is not a rationality >= 0")]
    Beta(f64),
}

/// Which of the paper's figures a grid reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Figure {
    /// Evaluative feedback: DREF against EF-p% and SAC (`dualrep train`).
    Fig3,
    /// Preference learning: DRPL against its baselines (`dualrep prefs`).
    Fig5,
    /// Simulated teachers that make mistakes: DREF against EF-100 over error rates, DRPL over
    /// the teacher's rationality (`report::robustness`).
    Robustness,
}

impl Figure {
    /// The methods a grid of this figure runs, as a refusal lists them.
    fn known_methods(self) -> &'static str {
        match self {
            Figure::Fig3 => {
                "dref, dref-authors, sac, sac-r100, dref-masked, ef-<p> (0 <= p <= 100), \
                 ef-dref, ef-dref-authors"
            }
            Figure::Fig5 | Figure::Robustness => "drpl, drpl-ss, fragment, full, drpl-mi",
        }
    }

    /// The file stem of the figure ("fig3").
    pub fn stem(self) -> &'static str {
        match self {
            Figure::Fig3 => "fig3",
            Figure::Fig5 => "fig5",
            Figure::Robustness => "robustness",
        }
    }

    /// The methods run when `--methods` is not given, in the paper's legend order (Figure 5:
    /// the paper's four, then DRPL-MI, ours).
    pub fn default_methods(self) -> &'static [&'static str] {
        match self {
            Figure::Fig3 => &["dref", "ef-100", "ef-50", "ef-25", "sac", MATCHED_EF],
            Figure::Fig5 => &["drpl", "drpl-ss", "fragment", "full", "drpl-mi"],
            Figure::Robustness => &["dref", "ef-100", "drpl"],
        }
    }
}

/// The grid's name for "EF at DREF's rate": it becomes `ef-<p>` per task once p is known.
pub const MATCHED_EF: &str = "ef-dref";
/// "EF at the authors' DREF's rate", the same for the `dref-authors` row.
pub const MATCHED_EF_AUTHORS: &str = "ef-dref-authors";

/// Each matched-rate row with the DREF row whose measured rate it takes.
pub const MATCHED_ROWS: [(&str, &str); 2] =
    [(MATCHED_EF, "dref"), (MATCHED_EF_AUTHORS, DREF_AUTHORS)];

/// The grid's name for exactly the authors' DREF.
pub const DREF_AUTHORS: &str = "dref-authors";

/// The grid's name for plain SAC at the env's own reward scale. The `sac` row follows the
/// authors, who ran Reaching's SAC baseline at reward 10 instead of 100 (`reward_scale=0.1`);
/// this row is the fair control beside it (tasks.md). On the other tasks both rows are the same
/// runs, so it is meant for `--tasks reaching`.
pub const SAC_UNSCALED: &str = "sac-r100";

/// The grid's name for the authors' DREF with its human critic regressed on queried steps only
/// (`human_critic_mask`, our choice in algorithms.md; the authors regress it on every sampled
/// step, the unqueried ones as H = 0). Not in the paper: a row beside the authors' DREF where
/// its query rule stops asking and the unqueried zeros wash out what the critic learnt
/// (fig3/README.md); the first of the product DREF's changes (docs/dref.md).
pub const DREF_MASKED: &str = "dref-masked";

/// The `--set` overrides a Figure 3 row adds on `task`, beyond the grid's own: the authors'
/// reward scale for Reaching's SAC baseline, the mask of DREF's masked row.
pub fn row_overrides(task: Task, method: &str) -> &'static [&'static str] {
    match (task, method) {
        (Task::Reaching, "sac") => &["reward_scale=0.1"],
        (_, DREF_MASKED) => &["human_critic_mask=true"],
        _ => &[],
    }
}

/// Queries per preference run (algorithms.md, section 3).
pub const DEFAULT_QUERIES: u32 = 40;

/// Everything that decides a grid's runs.
#[derive(Clone, Debug, PartialEq)]
pub struct GridConfig {
    pub figure: Figure,
    pub tasks: Vec<Task>,
    /// Seeds 0, 1, ..., seeds - 1.
    pub seeds: u64,
    /// Environment steps of every train run; `None` for the paper's per task.
    pub steps: Option<u64>,
    pub queries: u32,
    pub methods: Vec<String>,
    /// `key=value` overrides passed to every child as `--set key=value`.
    pub sets: Vec<String>,
    pub out: PathBuf,
}

/// One child process of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSpec {
    pub task: Task,
    pub method: String,
    pub seed: u64,
    pub dir: PathBuf,
    /// Arguments after the program name.
    pub args: Vec<String>,
}

impl RunSpec {
    /// "reaching/dref/seed3", for progress lines.
    pub fn label(&self) -> String {
        format!("{}/{}/seed{}", self.task.id(), self.method, self.seed)
    }
}

impl GridConfig {
    /// Checks the method names against what `train` and `prefs` accept, so that a typo fails
    /// before hours of runs rather than as a wall of failed children.
    pub fn validate(&self) -> Result<(), GridError> {
        if self.tasks.is_empty() || self.seeds == 0 || self.methods.is_empty() {
            return Err(GridError::Empty);
        }
        if self.figure == Figure::Robustness {
            return Err(GridError::RobustnessFigure);
        }
        for m in &self.methods {
            let ok = match self.figure {
                Figure::Fig3 => {
                    matches!(
                        m.as_str(),
                        "dref"
                            | DREF_AUTHORS
                            | "sac"
                            | MATCHED_EF
                            | MATCHED_EF_AUTHORS
                            | SAC_UNSCALED
                            | DREF_MASKED
                    ) || m
                        .strip_prefix("ef-")
                        .and_then(|p| p.parse::<f64>().ok())
                        .is_some_and(|p| (0.0..=100.0).contains(&p))
                }
                Figure::Fig5 | Figure::Robustness => {
                    Figure::Fig5.default_methods().contains(&m.as_str())
                }
            };
            if !ok {
                return Err(GridError::UnknownMethod {
                    method: m.clone(),
                    figure: self.figure,
                });
            }
        }
        Ok(())
    }

    /// Environment steps of a train run on `task`.
    pub fn steps_for(&self, task: Task) -> u64 {
        self.steps.unwrap_or_else(|| paper_steps(task))
    }

    /// The matched-rate rows the grid runs, each with the DREF row it follows.
    pub fn matched_rows(&self) -> Vec<(&'static str, &'static str)> {
        MATCHED_ROWS
            .into_iter()
            .filter(|(matched, _)| {
                self.figure == Figure::Fig3 && self.methods.iter().any(|m| m == matched)
            })
            .collect()
    }

    /// Whether `dref` (a DREF row's name) is in the grid (else its matched rate is the paper's).
    pub fn has(&self, dref: &str) -> bool {
        self.figure == Figure::Fig3 && self.methods.iter().any(|m| m == dref)
    }

    /// The run of `method` (a concrete name, never [`MATCHED_EF`]) on `task` with `seed`.
    pub fn spec(&self, task: Task, method: &str, seed: u64) -> RunSpec {
        let dir = run_dir(&self.out, task, method, seed);
        let (command, budget_flag, budget) = match self.figure {
            Figure::Fig3 | Figure::Robustness => {
                ("train", "--steps", self.steps_for(task).to_string())
            }
            Figure::Fig5 => ("prefs", "--queries", self.queries.to_string()),
        };
        // The fair SAC control is plain `train --method sac` at the env's reward scale; the
        // masked DREF row is `train --method dref-authors` with its mask set.
        let train_method = match method {
            SAC_UNSCALED => "sac",
            DREF_MASKED => DREF_AUTHORS,
            other => other,
        };
        let mut args: Vec<String> = [
            command,
            "--task",
            task.id(),
            "--method",
            train_method,
            budget_flag,
            &budget,
            "--seed",
            &seed.to_string(),
            "--out",
        ]
        .map(str::to_owned)
        .into();
        args.push(dir.to_string_lossy().into_owned());
        let row = match self.figure {
            Figure::Fig3 => row_overrides(task, method),
            Figure::Fig5 | Figure::Robustness => &[],
        };
        for kv in row
            .iter()
            .map(|s| s.to_string())
            .chain(self.sets.iter().cloned())
        {
            args.push("--set".into());
            args.push(kv);
        }
        RunSpec {
            task,
            method: method.into(),
            seed,
            dir,
            args,
        }
    }

    /// Every run that can start now: all but "EF at DREF's rate", DREF's runs first so that
    /// the matched runs, which wait for them, can start as early as possible.
    pub fn initial_runs(&self) -> Vec<RunSpec> {
        let mut methods: Vec<&str> = self
            .methods
            .iter()
            .map(String::as_str)
            .filter(|m| !MATCHED_ROWS.iter().any(|(matched, _)| m == matched))
            .collect();
        let followed = |m: &str| MATCHED_ROWS.iter().any(|(_, dref)| *dref == m);
        methods.sort_by_key(|m| !followed(m));
        let mut runs = Vec::new();
        for method in methods {
            for &task in &self.tasks {
                for seed in 0..self.seeds {
                    runs.push(self.spec(task, method, seed));
                }
            }
        }
        runs
    }

    /// The runs of "EF at DREF's rate" on `task` at `rate_pct` percent.
    pub fn matched_runs(&self, task: Task, rate_pct: f64) -> Vec<RunSpec> {
        let method = matched_ef_method(rate_pct);
        (0..self.seeds)
            .map(|seed| self.spec(task, &method, seed))
            .collect()
    }

    /// How many runs the whole grid has, the matched ones included.
    pub fn total_runs(&self) -> usize {
        self.tasks.len() * self.methods.len() * self.seeds as usize
    }
}

#[cfg(test)]
#[path = "grid_tests.rs"]
mod tests;
