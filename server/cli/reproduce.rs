//! `dualrep reproduce fig3|fig5`: runs the paper's experiment grid as `dualrep train` or
//! `dualrep prefs` runs, as child processes here or as Slurm job array tasks (`--executor`),
//! then writes `table.md` and the figure from every finished run. A grid stopped half-way
//! resumes: finished runs (those with a `summary.json`) are skipped.

mod progress;
mod robustness;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;

use crate::report::grid::{DEFAULT_QUERIES, Figure, GridConfig, RunSpec};
use crate::report::methods::paper_dref_rate;
use crate::report::run_files::{is_finished, read_train_summary, run_dir};
use crate::report::runner::{Outcome, RunStatus, Waiting, run_grid};
use crate::report::stats::mean_se;
use crate::report::write_report;
use crate::sim::Task;

use self::progress::Progress;
use super::grid_executor::{ExecutorArgs, ExecutorKind};

#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// fig3 (evaluative feedback: `dualrep train`), fig5 (preferences: `dualrep prefs`) or
    /// robustness (both, against simulated teachers that make mistakes).
    pub figure: Figure,
    /// Comma-separated tasks [default: lunar-lander,reaching,placing; robustness:
    /// reaching,placing].
    #[arg(long, value_delimiter = ',')]
    pub tasks: Vec<Task>,
    /// Seeds per method and task (0, 1, ..., N-1).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..))]
    pub seeds: u64,
    /// fig3: environment steps per run [default: the paper's, 150k for lunar-lander, 100k
    /// for the others; robustness: 30k].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub steps: Option<u64>,
    /// fig5: queries per run [default: 40].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub queries: Option<u32>,
    /// Comma-separated methods [default: fig3 dref,ef-100,ef-50,ef-25,sac,ef-dref; fig5
    /// drpl,drpl-ss,fragment,full,drpl-mi; robustness dref,ef-100,drpl]. `ef-dref` is EF at
    /// DREF's measured feedback rate, run once DREF's runs on that task have finished.
    /// `drpl-mi` (ours, not the paper's) is DRPL with the mutual-information pick among its
    /// candidate pairs (`acquisition = mutual_information`, which `--set acquisition=` can
    /// override).
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
    /// robustness: the teacher's error rates in percent, for the evaluative methods [default:
    /// 0,10,20,30].
    #[arg(long, value_delimiter = ',')]
    pub errors: Vec<u32>,
    /// robustness: the teacher's Boltzmann rationalities for the preference methods, numbers or
    /// `rational` [default: 0.5,1,2,5,10,20,rational].
    #[arg(long, value_delimiter = ',', value_parser = robustness::parse_beta)]
    pub betas: Vec<robustness::Beta>,
    /// A hyper-parameter override passed to every run as `--set KEY=VALUE` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// The grid's directory: runs go to OUT/<task>/<method>/seed<S>/.
    #[arg(long)]
    pub out: PathBuf,
    /// Run nothing: write table.md and the figure from the runs already finished in OUT.
    #[arg(long)]
    pub report_only: bool,
    #[command(flatten)]
    pub executor: ExecutorArgs,
}

pub fn run(args: ReproduceArgs, compute: &super::compute::Compute) -> anyhow::Result<()> {
    if args.report_only {
        if args.executor.no_wait {
            bail!("--report-only runs nothing, so --no-wait has nothing to do");
        }
        if !args.out.is_dir() {
            bail!("--report-only: {} is not a directory", args.out.display());
        }
        return report(args.figure, &args.out);
    }
    // Each run gets the cores its share allows (one each when the jobs fill the machine), and
    // every run computes with the kernels chosen here.
    let threads = args.executor.threads_per_run(compute.threads);
    let env = [
        ("DUALREP_THREADS".to_string(), threads.to_string()),
        (
            "DUALREP_KERNELS".to_string(),
            compute.path.name().to_string(),
        ),
    ];
    if args.figure == Figure::Robustness {
        return robustness::run(&args, &env);
    } else if !args.errors.is_empty() || !args.betas.is_empty() {
        bail!("--errors and --betas are for the robustness grid");
    }
    let config = grid_config(&args)?;
    let job_name = format!("dualrep-{}", config.figure.stem());
    let (mut executor, waiting) = args.executor.build(&config.out, &job_name, &env)?;

    let progress = Progress::new(config.total_runs());
    progress.line(&format!(
        "runs each on {threads} thread(s) with the {} kernels",
        compute.path
    ));
    let mut runs = config.initial_runs();
    let matched_rows = config.matched_rows();
    for &(_, dref) in &matched_rows {
        if config.has(dref) {
            continue;
        }
        for &task in &config.tasks {
            let rate = paper_dref_rate(task);
            progress.line(&format!(
                "{task}: {dref} is not in the grid; EF at its rate runs at the paper's {rate} %"
            ));
            runs.extend(config.matched_runs(task, rate));
        }
    }
    let mut dref_ended: HashMap<(Task, &str), u64> = HashMap::new();
    let follow_up = |outcome: &Outcome| -> Vec<RunSpec> {
        let Some(&(_, dref)) = matched_rows
            .iter()
            .find(|(_, dref)| outcome.spec.method == *dref)
        else {
            return Vec::new();
        };
        let task = outcome.spec.task;
        let ended = dref_ended.entry((task, dref)).or_default();
        *ended += 1;
        if *ended < config.seeds {
            return Vec::new();
        }
        let rate = measured_dref_rate(&config, task, dref).unwrap_or_else(|| {
            let rate = paper_dref_rate(task);
            progress.line(&format!(
                "{task}: no {dref} run finished; EF at its rate runs at the paper's {rate} %"
            ));
            rate
        });
        progress.line(&format!(
            "{task}: {dref} asked on {rate:.2} % of steps; queuing EF at that rate"
        ));
        config.matched_runs(task, rate)
    };
    if waiting == Waiting::UntilDone && args.executor.executor == ExecutorKind::Slurm {
        progress.line(
            "waiting for the Slurm queue (Ctrl-C stops the waiting, not the runs; the same \
             command picks them up again)",
        );
    }
    let grid = run_grid(&mut *executor, runs, waiting, follow_up, |event| {
        progress.event(&event)
    });
    progress.finish();
    let grid = grid.context(
        "the grid stopped; runs already handed to the executor go on (Slurm keeps its \
         queue), and the same command picks them up again",
    )?;
    if waiting == Waiting::NoWait {
        return report_submitted(&config, &grid.outcomes, grid.in_flight, &dref_ended);
    }
    let outcomes = grid.outcomes;

    let failed: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| matches!(o.status, RunStatus::Failed(_)))
        .collect();
    let ran = outcomes
        .iter()
        .filter(|o| o.status != RunStatus::Skipped)
        .count();
    println!(
        "{} runs: {} ran, {} already finished, {} failed",
        outcomes.len(),
        ran,
        outcomes.len() - ran,
        failed.len()
    );
    report(config.figure, &config.out)?;
    if !failed.is_empty() {
        for o in &failed {
            if let RunStatus::Failed(why) = &o.status {
                eprintln!("failed: {}: {why}", o.spec.label());
            }
        }
        bail!(
            "{} of {} runs failed (their stderr.log is in their run directory); run the same command again to retry them",
            failed.len(),
            outcomes.len()
        );
    }
    Ok(())
}

/// After `--no-wait`: where the runs are, and what comes next.
fn report_submitted(
    config: &GridConfig,
    outcomes: &[Outcome],
    in_flight: usize,
    dref_ended: &HashMap<(Task, &str), u64>,
) -> anyhow::Result<()> {
    let finished = outcomes
        .iter()
        .filter(|o| o.status == RunStatus::Skipped)
        .count();
    println!(
        "{} runs: {in_flight} in the Slurm queue, {finished} already finished",
        config.total_runs()
    );
    for (_, dref) in config.matched_rows() {
        if !config.has(dref) {
            continue;
        }
        let later: Vec<&str> = config
            .tasks
            .iter()
            .filter(|&&t| dref_ended.get(&(t, dref)).copied().unwrap_or(0) < config.seeds)
            .map(|t| t.id())
            .collect();
        if !later.is_empty() {
            println!(
                "EF at {dref}'s rate on {} is submitted by a later run of this command, once \
                 {dref}'s runs there have finished",
                later.join(", ")
            );
        }
    }
    println!(
        "run the same command again to wait for the runs (it submits only what is missing or \
         failed), or add --report-only for table.md and the figure from what has finished"
    );
    Ok(())
}

/// The grid the arguments describe, checked before anything runs.
fn grid_config(args: &ReproduceArgs) -> anyhow::Result<GridConfig> {
    match (args.figure, args.steps, args.queries) {
        (Figure::Fig5, Some(_), _) => bail!("--steps is for fig3; fig5 runs take --queries"),
        (Figure::Fig3, _, Some(_)) => bail!("--queries is for fig5; fig3 runs take --steps"),
        _ => {}
    }
    if let Some(bad) = args.sets.iter().find(|kv| !kv.contains('=')) {
        bail!("--set {bad:?}: expected KEY=VALUE");
    }
    let mut methods: Vec<String> = if args.methods.is_empty() {
        args.figure
            .default_methods()
            .iter()
            .map(|m| m.to_string())
            .collect()
    } else {
        args.methods.iter().map(|m| m.trim().to_string()).collect()
    };
    dedup_keep_order(&mut methods);
    let mut tasks = if args.tasks.is_empty() {
        vec![Task::LunarLander, Task::Reaching, Task::Placing]
    } else {
        args.tasks.clone()
    };
    dedup_keep_order(&mut tasks);
    let config = GridConfig {
        figure: args.figure,
        tasks,
        seeds: args.seeds,
        steps: args.steps,
        queries: args.queries.unwrap_or(DEFAULT_QUERIES),
        methods,
        sets: args.sets.clone(),
        out: args.out.clone(),
    };
    config.validate()?;
    Ok(config)
}

pub(super) fn dedup_keep_order<T: PartialEq + Clone>(items: &mut Vec<T>) {
    let mut seen: Vec<T> = Vec::with_capacity(items.len());
    items.retain(|x| {
        let new = !seen.contains(x);
        if new {
            seen.push(x.clone());
        }
        new
    });
}

/// The DREF row `dref`'s mean feedback percentage over its finished seeds on `task`, read from
/// their summaries; `None` when none finished (or none could be read).
fn measured_dref_rate(config: &GridConfig, task: Task, dref: &str) -> Option<f64> {
    let rates: Vec<f64> = (0..config.seeds)
        .map(|seed| run_dir(&config.out, task, dref, seed))
        .filter(|dir| is_finished(dir))
        .filter_map(|dir| read_train_summary(&dir).ok())
        .map(|s| 100.0 * s.feedback_fraction)
        .collect();
    (!rates.is_empty()).then(|| mean_se(&rates).mean)
}

pub(super) fn report(figure: Figure, out: &Path) -> anyhow::Result<()> {
    let written = write_report(figure, out)?;
    println!(
        "{} finished runs -> {}, {}, {}",
        written.runs,
        written.table.display(),
        written.svg.display(),
        written.png.display()
    );
    Ok(())
}
