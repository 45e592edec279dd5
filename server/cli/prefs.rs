//! `dualrep prefs`: one preference-learning run (DRPL or a baseline) with the synthetic oracle,
//! writing `alignment.csv` (row 0 is the prior, then a row per query, flushed as it happens),
//! `queries.jsonl` (what was asked and answered) and `summary.json` (written last, atomically:
//! its presence marks a finished run for `reproduce fig5`).

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use super::arg_error::ArgError;
use super::output::publish_summary;
use super::overrides;
use super::progress::Progress;
use super::remote::RemoteArgs;
use crate::guidance::drpl::acquisition::Acquisition;
use crate::guidance::drpl::features;
use crate::guidance::drpl::pool::{Clip, QueryPool};
use crate::guidance::drpl::run::{PreferenceRun, PreferenceRunConfig, QueryReport};
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::drpl::simulated_teacher::SimulatedTeacher;
use crate::guidance::drpl::trainer::Preference;
use crate::remote_env::RemoteEnv;
use crate::sim::Task;

#[derive(Debug, Args)]
pub struct PrefsArgs {
    /// reaching, placing or lunar-lander (with `--env-url`: the task the remote env copies).
    #[arg(long)]
    pub task: Option<Task>,
    /// drpl, drpl-ss, fragment or full (the paper's), or drpl-mi: DRPL with the
    /// mutual-information pick among its candidate pairs (ours).
    #[arg(long)]
    pub method: QueryMethod,
    /// Queries to ask (each answered by the synthetic oracle).
    #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..))]
    pub queries: u32,
    /// Seeds the trajectories, theta_true, the pair draws and the belief's sampler.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Random-policy trajectories to record [default: 100]; wins over `--set trajectories=`.
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..))]
    pub trajectories: Option<u64>,
    /// The pick among candidates: uniform (the paper's) or mutual-information [default:
    /// uniform; drpl-mi: mutual-information]; wins over `--set acquisition=`.
    #[arg(long, value_parser = parse_acquisition)]
    pub acquisition: Option<Acquisition>,
    #[command(flatten)]
    pub overrides: overrides::OverrideArgs,
    #[command(flatten)]
    pub remote: RemoteArgs,
}

fn parse_acquisition(s: &str) -> Result<Acquisition, ArgError> {
    match s {
        "uniform" => Ok(Acquisition::Uniform),
        "mutual-information" => Ok(Acquisition::MutualInformation),
        _ => Err(ArgError::Acquisition(s.to_string())),
    }
}

/// `summary.json`.
#[derive(Debug, Serialize)]
pub struct PrefsSummary {
    /// The task's name (a declared task's: its env's id).
    pub task: String,
    /// The remote env the trajectories were recorded on, if not our simulator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env_url: Option<String>,
    pub method: QueryMethod,
    pub seed: u64,
    /// Queries asked (fewer than requested only if the method ran out of new pairs).
    pub queries: usize,
    pub requested_queries: u32,
    pub final_alignment: f64,
    pub final_alignment_of_mean: f64,
    pub mean_segment_length: f64,
    pub segments: usize,
    pub trajectories: usize,
    /// Median wall time of one belief update; `null` if no answer updated the belief.
    pub belief_update_ms_median: Option<f64>,
    pub theta_true: Vec<f64>,
    pub feature_names: Vec<String>,
    pub wall_seconds: f64,
    pub config: PreferenceRunConfig,
}

/// One side of a query in `queries.jsonl`.
#[derive(Debug, Serialize)]
struct ClipLine<'a> {
    trajectory: usize,
    start: usize,
    end: usize,
    /// Predicate 0 first; `null` for windows and whole trajectories.
    abstract_state: Option<String>,
    /// Standardised, as the belief and the oracle saw them.
    features: &'a [f64],
    raw_features: &'a [f64],
}

/// One line of `queries.jsonl`.
#[derive(Debug, Serialize)]
struct QueryLine<'a> {
    query: usize,
    predicate: Option<&'static str>,
    left: ClipLine<'a>,
    right: ClipLine<'a>,
    answer: Preference,
    alignment: f64,
    alignment_of_mean: f64,
    belief_update_ms: Option<f64>,
}

fn clip_line(clip: &Clip, graph_dim: usize) -> ClipLine<'_> {
    ClipLine {
        trajectory: clip.trajectory,
        start: clip.start,
        end: clip.end,
        abstract_state: clip.abstract_state.map(|g| g.to_bit_string(graph_dim)),
        features: &clip.features,
        raw_features: &clip.raw_features,
    }
}

/// The run's config: defaults (our task's, or those of the task a remote env declared), then
/// the TOML file, then `--set`, then the dedicated flags.
pub fn resolve_config(
    args: &PrefsArgs,
    remote: Option<&RemoteEnv>,
) -> anyhow::Result<PreferenceRunConfig> {
    let settings = args.overrides.settings()?;
    let config = match (args.task, remote) {
        (Some(task), _) => settings.preference(task, args.method, args.seed),
        (None, Some(env)) => {
            let d = env.description();
            settings.apply_preference(PreferenceRunConfig::declared(
                d.declared_task(),
                d.graph,
                args.method,
                args.seed,
                d.spec.max_episode_steps as usize,
            ))
        }
        (None, None) => anyhow::bail!("give --task, --env-url, or both"),
    };
    let mut config = config?;
    if let Some(n) = args.trajectories {
        config.trajectories = usize::try_from(n)?;
    }
    if let Some(a) = args.acquisition {
        config.acquisition = a;
    }
    Ok(config)
}

fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    })
}

pub fn run(args: PrefsArgs) -> anyhow::Result<()> {
    let mut remote = args.remote.connect(args.task)?;
    let config = resolve_config(&args, remote.as_ref())?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let start = Instant::now();
    let mut run = match remote.as_mut() {
        None => PreferenceRun::new(config.clone()),
        Some(env) => {
            let trajs = PreferenceRun::record_trajectories_on(&config, env, &mut |_| {})
                .context("recording the trajectories")?;
            let pool = QueryPool::from_trajectories(&config.task, &trajs, config.min_run);
            PreferenceRun::with_pool(config.clone(), pool)
        }
    };
    let mut oracle = SimulatedTeacher::new(
        run.theta_true().to_vec(),
        config.teacher,
        run.teacher_seed(),
        run.pool(),
    );
    let graph = config.scene_graph;

    let csv_path = args.out.join("alignment.csv");
    let mut csv = BufWriter::new(
        File::create(&csv_path).with_context(|| format!("creating {}", csv_path.display()))?,
    );
    writeln!(csv, "query,alignment,alignment_of_mean")?;
    writeln!(csv, "0,{},{}", run.alignment(), run.alignment_of_mean())?;
    csv.flush()?;
    let jsonl_path = args.out.join("queries.jsonl");
    let mut jsonl = BufWriter::new(
        File::create(&jsonl_path).with_context(|| format!("creating {}", jsonl_path.display()))?,
    );

    let label = format!("{} {} seed {}", config.task, args.method, args.seed);
    let mut progress = Progress::new(u64::from(args.queries), label);
    let mut update_ms = Vec::new();
    while run.queries() < args.queries as usize {
        let Some(report) = run.step(&mut oracle) else {
            eprintln!(
                "{}: no new pair left after {} queries; stopping early",
                args.method,
                run.queries()
            );
            break;
        };
        write_query(&mut csv, &mut jsonl, &report, &graph)?;
        update_ms.extend(report.update_ms);
        progress.update(report.query as u64, || {
            format!("alignment {:.3}", report.alignment)
        });
    }
    progress.finish();

    let summary = PrefsSummary {
        task: config.task.id().to_string(),
        env_url: args.remote.env_url.clone(),
        method: args.method,
        seed: args.seed,
        queries: run.queries(),
        requested_queries: args.queries,
        final_alignment: run.alignment(),
        final_alignment_of_mean: run.alignment_of_mean(),
        mean_segment_length: run.pool().mean_segment_length(),
        segments: run.pool().segments().len(),
        trajectories: run.pool().trajectories(),
        belief_update_ms_median: median(&mut update_ms),
        theta_true: run.theta_true().to_vec(),
        feature_names: features::names_of(&config.task),
        wall_seconds: start.elapsed().as_secs_f64(),
        config,
    };
    publish_summary(&args.out.join("summary.json"), &summary)
}

/// Append one query to `alignment.csv` and `queries.jsonl`, flushed so a watcher sees it.
fn write_query(
    csv: &mut impl Write,
    jsonl: &mut impl Write,
    report: &QueryReport,
    graph: &crate::scene_graph::SceneGraph,
) -> anyhow::Result<()> {
    writeln!(
        csv,
        "{},{},{}",
        report.query, report.alignment, report.alignment_of_mean
    )?;
    csv.flush()?;
    let dim = graph.dim();
    let line = QueryLine {
        query: report.query,
        predicate: report.pair.predicate.map(|i| graph.predicates()[i].name),
        left: clip_line(&report.pair.left, dim),
        right: clip_line(&report.pair.right, dim),
        answer: report.preference,
        alignment: report.alignment,
        alignment_of_mean: report.alignment_of_mean,
        belief_update_ms: report.update_ms,
    };
    serde_json::to_writer(&mut *jsonl, &line)?;
    writeln!(jsonl)?;
    jsonl.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_none() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&mut []), None);
    }
}
