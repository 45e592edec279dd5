//! `dualrep reproduce robustness`: the robustness grid (`report::robustness`) through the same
//! executors as the paper's figures, then its `table.md` and `robustness.svg` / `.png`.

use anyhow::{Context, bail};

use super::progress::Progress;
use super::{ReproduceArgs, dedup_keep_order, report};
use crate::cli::arg_error::ArgError;
use crate::report::grid::{DEFAULT_QUERIES, Figure};
use crate::report::robustness::{DEFAULT_BETAS, DEFAULT_ERRORS, DEFAULT_STEPS, RobustnessConfig};
use crate::report::runner::{RunStatus, Waiting, run_grid};
use crate::sim::Task;

/// A teacher's rationality on the command line: a number or `rational`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beta(pub Option<f64>);

pub fn parse_beta(s: &str) -> Result<Beta, ArgError> {
    match s.trim() {
        "rational" => Ok(Beta(None)),
        t => t
            .parse::<f64>()
            .ok()
            .filter(|b| b.is_finite() && *b >= 0.0)
            .map(|b| Beta(Some(b)))
            .ok_or_else(|| ArgError::Beta(s.to_string())),
    }
}

fn config(args: &ReproduceArgs) -> anyhow::Result<RobustnessConfig> {
    if let Some(bad) = args.sets.iter().find(|kv| !kv.contains('=')) {
        bail!("--set {bad:?}: expected KEY=VALUE");
    }
    let mut methods: Vec<String> = if args.methods.is_empty() {
        Figure::Robustness
            .default_methods()
            .iter()
            .map(|m| m.to_string())
            .collect()
    } else {
        args.methods.iter().map(|m| m.trim().to_string()).collect()
    };
    dedup_keep_order(&mut methods);
    let preference = Figure::Fig5.default_methods();
    let (prefs_methods, train_methods): (Vec<String>, Vec<String>) = methods
        .into_iter()
        .partition(|m| preference.contains(&m.as_str()));
    if let Some(bad) = train_methods.iter().find(|m| {
        m.parse::<crate::guidance::feedback_schedule::EvaluativeMethod>()
            .is_err()
    }) {
        bail!(
            "unknown method {bad:?} for robustness: expected dref, sac, ef-<p>, drpl, drpl-ss, fragment, full or drpl-mi"
        );
    }
    let mut tasks = if args.tasks.is_empty() {
        vec![Task::Reaching, Task::Placing]
    } else {
        args.tasks.clone()
    };
    dedup_keep_order(&mut tasks);
    if args.queries.is_some() && prefs_methods.is_empty() {
        bail!("--queries is for the preference methods, and none is in --methods");
    }
    if args.steps.is_some() && train_methods.is_empty() {
        bail!("--steps is for the evaluative methods, and none is in --methods");
    }
    let config = RobustnessConfig {
        tasks,
        seeds: args.seeds,
        steps: args.steps.unwrap_or(DEFAULT_STEPS),
        queries: args.queries.unwrap_or(DEFAULT_QUERIES),
        train_methods,
        prefs_methods,
        errors: if args.errors.is_empty() {
            DEFAULT_ERRORS.to_vec()
        } else {
            args.errors.clone()
        },
        betas: if args.betas.is_empty() {
            DEFAULT_BETAS.to_vec()
        } else {
            args.betas.iter().map(|b| b.0).collect()
        },
        sets: args.sets.clone(),
        out: args.out.clone(),
    };
    config.validate()?;
    Ok(config)
}

/// Run the grid; every run gets `env` (its threads and kernels) in its environment.
pub fn run(args: &ReproduceArgs, env: &[(String, String)]) -> anyhow::Result<()> {
    let config = config(args)?;
    let (mut executor, waiting) = args
        .executor
        .build(&config.out, "dualrep-robustness", env)?;
    let runs = config.runs();
    let progress = Progress::new(runs.len());
    let grid = run_grid(
        &mut *executor,
        runs,
        waiting,
        |_| Vec::new(),
        |event| progress.event(&event),
    );
    progress.finish();
    let grid = grid.context(
        "the grid stopped; runs already handed to the executor go on, and the same command \
         picks them up again",
    )?;
    if waiting == Waiting::NoWait {
        println!(
            "{} runs in the Slurm queue; run the same command again to wait for them",
            grid.in_flight
        );
        return Ok(());
    }
    let failed: Vec<_> = grid
        .outcomes
        .iter()
        .filter_map(|o| match &o.status {
            RunStatus::Failed(why) => Some((o.spec.label(), why.clone())),
            _ => None,
        })
        .collect();
    report(Figure::Robustness, &config.out)?;
    for (label, why) in &failed {
        eprintln!("failed: {label}: {why}");
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} runs failed (their stderr.log is in their run directory); run the same command again to retry them",
            failed.len(),
            grid.outcomes.len()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn betas_parse_as_numbers_or_rational() {
        assert_eq!(parse_beta("2.5"), Ok(Beta(Some(2.5))));
        assert_eq!(parse_beta("rational"), Ok(Beta(None)));
        assert!(parse_beta("-1").is_err());
        assert!(parse_beta("x").is_err());
    }
}
