//! `reproduce robustness`: how the methods hold up against simulated teachers that make
//! mistakes (algorithms.md section 4, after B-Pref). DREF against EF-100 with teachers that flip
//! 0, 10, 20 and 30 % of their answers (`teacher_error`), and DRPL's final alignment against the
//! teacher's Boltzmann rationality (`teacher_beta`, plus the perfectly rational teacher).
//!
//! Pure: the grid (which runs, their directories and command lines), the aggregation of
//! finished runs and `table.md`. Runs live in `OUT/<task>/<method>-err<E>/seed<S>/` and
//! `OUT/<task>/<method>-beta<B>/seed<S>/` (`-rational` for the perfect teacher), so one grid
//! folder holds both sweeps and the directory says what each run is.

use std::fmt::Write;
use std::path::PathBuf;

use super::grid::{GridError, RunSpec};
use super::methods::{display_name, task_rank, task_title};
use super::run_files::{PrefsRun, TrainRun, run_dir};
use super::stats::{MeanSe, mean_se};
use crate::sim::Task;

/// The error rates of the evaluative sweep, in percent (the grid).
pub const DEFAULT_ERRORS: [u32; 4] = [0, 10, 20, 30];
/// The Boltzmann rationalities of the preference sweep; `None` is the perfectly rational
/// teacher (the paper's oracle).
pub const DEFAULT_BETAS: [Option<f64>; 7] = [
    Some(0.5),
    Some(1.0),
    Some(2.0),
    Some(5.0),
    Some(10.0),
    Some(20.0),
    None,
];
/// Environment steps of a train run when `--steps` is not given: a budget this 2-core machine
/// finishes (the paper's 100k would be about three times as long).
pub const DEFAULT_STEPS: u64 = 30_000;

/// Everything that decides the robustness grid.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustnessConfig {
    pub tasks: Vec<Task>,
    pub seeds: u64,
    pub steps: u64,
    pub queries: u32,
    /// Evaluative methods (`dref`, `ef-<p>`, `sac`): swept over `errors`.
    pub train_methods: Vec<String>,
    /// Preference methods (`drpl`, ...): swept over `betas`.
    pub prefs_methods: Vec<String>,
    pub errors: Vec<u32>,
    pub betas: Vec<Option<f64>>,
    /// `key=value` overrides passed to every run.
    pub sets: Vec<String>,
    pub out: PathBuf,
}

/// A teacher's fault level as a directory suffix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Level {
    /// `teacher_error` in percent.
    Error(u32),
    /// `teacher_beta`; `None`: rational.
    Beta(Option<f64>),
}

impl Level {
    fn suffix(self) -> String {
        match self {
            Level::Error(e) => format!("err{e}"),
            Level::Beta(Some(b)) => format!("beta{b}"),
            Level::Beta(None) => "rational".into(),
        }
    }

    /// The `--set` that makes the teacher so (none for the perfect teacher).
    fn set(self) -> Option<String> {
        match self {
            Level::Error(0) | Level::Beta(None) => None,
            Level::Error(e) => Some(format!("teacher_error={}", f64::from(e) / 100.0)),
            Level::Beta(Some(b)) => Some(format!("teacher_beta={b}")),
        }
    }
}

/// `dref-err10` -> (`dref`, error 10 %); `drpl-beta2` -> (`drpl`, beta 2); `drpl-rational`.
pub fn parse_label(label: &str) -> Option<(String, Level)> {
    if let Some(method) = label.strip_suffix("-rational") {
        return Some((method.into(), Level::Beta(None)));
    }
    let (method, suffix) = label.rsplit_once('-')?;
    if let Some(e) = suffix.strip_prefix("err") {
        return Some((method.into(), Level::Error(e.parse().ok()?)));
    }
    let b: f64 = suffix.strip_prefix("beta")?.parse().ok()?;
    Some((method.into(), Level::Beta(Some(b))))
}

impl RobustnessConfig {
    pub fn validate(&self) -> Result<(), GridError> {
        if self.tasks.is_empty() || self.seeds == 0 {
            return Err(GridError::NoTaskOrSeed);
        }
        if self.train_methods.is_empty() && self.prefs_methods.is_empty() {
            return Err(GridError::NoMethod);
        }
        if let Some(e) = self.errors.iter().find(|e| **e >= 100) {
            return Err(GridError::ErrorRate(*e));
        }
        if let Some(b) = self
            .betas
            .iter()
            .flatten()
            .find(|b| !(b.is_finite() && **b >= 0.0))
        {
            return Err(GridError::Beta(*b));
        }
        Ok(())
    }

    fn run(&self, task: Task, method: &str, level: Level, seed: u64) -> RunSpec {
        let label = format!("{method}-{}", level.suffix());
        let dir = run_dir(&self.out, task, &label, seed);
        let (command, budget_flag, budget) = match level {
            Level::Error(_) => ("train", "--steps", self.steps.to_string()),
            Level::Beta(_) => ("prefs", "--queries", self.queries.to_string()),
        };
        let mut args: Vec<String> = [
            command,
            "--task",
            task.id(),
            "--method",
            method,
            budget_flag,
            &budget,
            "--seed",
            &seed.to_string(),
            "--out",
        ]
        .map(str::to_owned)
        .into();
        args.push(dir.to_string_lossy().into_owned());
        for kv in level.set().into_iter().chain(self.sets.iter().cloned()) {
            args.push("--set".into());
            args.push(kv);
        }
        RunSpec {
            task,
            method: label,
            seed,
            dir,
            args,
        }
    }

    /// Every run: the preference sweep first (seconds each), then the evaluative one task by
    /// task, so that whole tasks finish early.
    pub fn runs(&self) -> Vec<RunSpec> {
        let mut runs = Vec::new();
        for &task in &self.tasks {
            for method in &self.prefs_methods {
                for &beta in &self.betas {
                    for seed in 0..self.seeds {
                        runs.push(self.run(task, method, Level::Beta(beta), seed));
                    }
                }
            }
        }
        for &task in &self.tasks {
            for seed in 0..self.seeds {
                for &e in &self.errors {
                    for method in &self.train_methods {
                        runs.push(self.run(task, method, Level::Error(e), seed));
                    }
                }
            }
        }
        runs
    }
}

/// One method at one error rate on one task.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorCell {
    pub method: String,
    pub error: u32,
    /// Cumulative reward at the end of training.
    pub cumulative: MeanSe,
    /// Share of steps with feedback, in percent.
    pub feedback_pct: MeanSe,
    /// Mean return of the last ten episodes.
    pub final_return: MeanSe,
    pub steps: u64,
}

/// One preference method at one rationality on one task.
#[derive(Clone, Debug, PartialEq)]
pub struct BetaCell {
    pub method: String,
    pub beta: Option<f64>,
    pub final_alignment: MeanSe,
}

/// A task's results.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustnessTask {
    pub task: Task,
    pub errors: Vec<ErrorCell>,
    pub betas: Vec<BetaCell>,
}

/// Groups finished runs by task, method and fault level (directories that are not this
/// grid's are passed over).
pub fn aggregate(train: &[TrainRun], prefs: &[PrefsRun]) -> Vec<RobustnessTask> {
    let mut tasks: Vec<Task> = train
        .iter()
        .map(|r| r.key.task)
        .chain(prefs.iter().map(|r| r.key.task))
        .collect();
    tasks.sort_by_key(|t| task_rank(*t));
    tasks.dedup();
    tasks
        .into_iter()
        .map(|task| {
            let mut errors: Vec<ErrorCell> = Vec::new();
            let mut cells: Vec<(String, u32)> = train
                .iter()
                .filter(|r| r.key.task == task)
                .filter_map(|r| match parse_label(&r.key.method)? {
                    (m, Level::Error(e)) => Some((m, e)),
                    _ => None,
                })
                .collect();
            cells.sort_by(|a, b| (a.1, &a.0).cmp(&(b.1, &b.0)));
            cells.dedup();
            for (method, error) in cells {
                let runs: Vec<&TrainRun> = train
                    .iter()
                    .filter(|r| {
                        r.key.task == task
                            && parse_label(&r.key.method)
                                == Some((method.clone(), Level::Error(error)))
                    })
                    .collect();
                let of = |f: &dyn Fn(&TrainRun) -> f64| {
                    mean_se(&runs.iter().map(|r| f(r)).collect::<Vec<_>>())
                };
                errors.push(ErrorCell {
                    cumulative: of(&|r| r.summary.cumulative_return),
                    feedback_pct: of(&|r| 100.0 * r.summary.feedback_fraction),
                    final_return: of(&|r| r.summary.final_mean_return),
                    steps: runs.iter().map(|r| r.summary.steps).min().unwrap_or(0),
                    method,
                    error,
                });
            }
            let mut betas: Vec<BetaCell> = Vec::new();
            for r in prefs.iter().filter(|r| r.key.task == task) {
                let Some((method, Level::Beta(beta))) = parse_label(&r.key.method) else {
                    continue;
                };
                if betas.iter().any(|c| c.method == method && c.beta == beta) {
                    continue;
                }
                let values: Vec<f64> = prefs
                    .iter()
                    .filter(|p| {
                        p.key.task == task
                            && parse_label(&p.key.method)
                                == Some((method.clone(), Level::Beta(beta)))
                    })
                    .map(|p| p.summary.final_alignment)
                    .collect();
                betas.push(BetaCell {
                    method,
                    beta,
                    final_alignment: mean_se(&values),
                });
            }
            // Rising rationality, the rational teacher last.
            betas.sort_by(|a, b| {
                let key = |c: &BetaCell| c.beta.unwrap_or(f64::INFINITY);
                (a.method.as_str(), key(a))
                    .partial_cmp(&(b.method.as_str(), key(b)))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            RobustnessTask {
                task,
                errors,
                betas,
            }
        })
        .collect()
}

fn fmt(m: MeanSe, decimals: usize) -> String {
    if m.mean.is_nan() {
        return "–".into();
    }
    format!("{:.*} ± {:.*}", decimals, m.mean, decimals, m.se)
}

/// `table.md`: per task, the error sweep (with each method's reward as a ratio to the first
/// method at the same error rate, DREF to EF-100 in the default grid) and the beta sweep.
pub fn table(tasks: &[RobustnessTask]) -> String {
    let mut out = String::from("# Robustness to simulated teachers' mistakes\n\n");
    out.push_str(
        "Cumulative reward over all finished episodes at the end of training and the share of \
         steps with feedback, mean ± standard error over seeds, against the teacher's error rate \
         (`teacher_error`: the share of answers flipped); DRPL's final alignment against the \
         teacher's Boltzmann rationality (`teacher_beta`; \"rational\" is the paper's \
         deterministic oracle). n is the number of seeds that finished.\n",
    );
    for t in tasks {
        let _ = write!(out, "\n## {}\n", task_title(t.task));
        if !t.errors.is_empty() {
            let methods: Vec<&str> = {
                let mut m: Vec<&str> = t.errors.iter().map(|c| c.method.as_str()).collect();
                m.sort_by_key(|m| super::methods::order_key(m));
                m.dedup();
                m
            };
            // DREF is compared with EF-100 (the grid's default); otherwise with the last.
            let reference_method = if methods.contains(&"ef-100") {
                "ef-100"
            } else {
                methods[methods.len() - 1]
            };
            let steps = t.errors.iter().map(|c| c.steps).min().unwrap_or(0);
            let _ = writeln!(out, "\nEvaluative feedback, {steps} steps:\n");
            out.push_str(
                "| error | method | n | cumulative reward | ratio | feedback | final return |\n",
            );
            out.push_str("|---|---|---|---|---|---|---|\n");
            let mut errors: Vec<u32> = t.errors.iter().map(|c| c.error).collect();
            errors.dedup();
            for e in errors {
                let reference = t
                    .errors
                    .iter()
                    .find(|c| c.error == e && c.method == reference_method)
                    .map(|c| c.cumulative.mean);
                for m in &methods {
                    let Some(c) = t.errors.iter().find(|c| c.error == e && c.method == *m) else {
                        continue;
                    };
                    let ratio = match reference {
                        Some(r) if r > 0.0 && c.cumulative.mean.is_finite() => {
                            format!("{:.2}", c.cumulative.mean / r)
                        }
                        _ => "–".into(),
                    };
                    let _ = writeln!(
                        out,
                        "| {e} % | {} | {} | {} | {ratio} | {} % | {} |",
                        display_name(m),
                        c.cumulative.n,
                        fmt(c.cumulative, 0),
                        fmt(c.feedback_pct, 1),
                        fmt(c.final_return, 1),
                    );
                }
            }
            if methods.len() > 1 {
                let _ = writeln!(
                    out,
                    "\nratio: cumulative reward over {}'s at the same error rate.",
                    display_name(reference_method)
                );
            }
        }
        if !t.betas.is_empty() {
            out.push_str("\nPreferences, final alignment:\n\n| teacher_beta | method | n | final alignment |\n|---|---|---|---|\n");
            for c in &t.betas {
                let beta = c.beta.map_or("rational".to_string(), |b| b.to_string());
                let _ = writeln!(
                    out,
                    "| {beta} | {} | {} | {} |",
                    display_name(&c.method),
                    c.final_alignment.n,
                    fmt(c.final_alignment, 3)
                );
            }
        }
    }
    out
}

#[cfg(test)]
#[path = "robustness_tests.rs"]
mod tests;
