//! Reading the files that `dualrep train` and `dualrep prefs` leave in a run directory, and
//! finding the finished runs of a grid laid out as `DIR/<task>/<method>/seed<S>/`.
//!
//! This is the report's only reading IO; everything downstream works on the plain structs here.
//! The summaries are read leniently (unknown fields ignored, the non-essential ones optional),
//! because `train` and `prefs` may add fields and only "at least" these are promised.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Deserialize;

use crate::guidance::evaluative_run::{GraphAtEpisodeEnd, TimeLimitEnd};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::settings::time_limit_as_run;
use crate::sim::Task;

/// The file whose presence marks a run as finished (written last by `train` and `prefs`).
pub const SUMMARY_FILE: &str = "summary.json";

/// One row of `metrics.csv`: one finished episode.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct EpisodeRow {
    pub step: u64,
    pub episode: u64,
    #[serde(rename = "return")]
    pub episode_return: f64,
    /// Steps of the episode (absent from files written before it was a column).
    #[serde(default)]
    pub length: Option<u32>,
    /// How the episode ended: success, failure or time_limit (absent from older files).
    #[serde(default)]
    pub outcome: Option<crate::sim::Outcome>,
    pub cumulative_return: f64,
    pub feedback_count: u64,
    /// Share of environment steps so far with feedback, in [0, 1].
    pub feedback_fraction: f64,
    /// Steps since the rule last asked, at the episode's end (absent from older files).
    #[serde(default)]
    pub steps_since_query: Option<u64>,
    /// The longest stretch of consecutive asked steps so far (absent from older files).
    #[serde(default)]
    pub longest_flood: Option<u64>,
}

/// `summary.json` of a `train` run.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct TrainSummary {
    pub task: String,
    pub method: String,
    pub seed: u64,
    pub steps: u64,
    pub cumulative_return: f64,
    pub feedback_count: u64,
    /// In [0, 1]; the report shows it as a percentage.
    pub feedback_fraction: f64,
    pub final_mean_return: f64,
    #[serde(default)]
    pub wall_seconds: Option<f64>,
    #[serde(default)]
    pub updates_per_second: Option<f64>,
    /// The longest stretch of consecutive asked steps from step 2,000 on (absent from runs
    /// written before it was measured).
    #[serde(default)]
    pub longest_flood_after_2k: Option<u64>,
    /// The run's configuration as it ran (only what the report reads).
    #[serde(default)]
    pub config: RunConfigSeen,
}

/// What the report reads of a run's configuration.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
pub struct RunConfigSeen {
    /// `reset` for the authors' runs as run (`profile = "as-run"` sets it on every task).
    #[serde(default)]
    pub graph_at_episode_end: GraphAtEpisodeEnd,
    /// How a time limit's end was stored (runs written before the setting: as a truncation).
    #[serde(default)]
    pub time_limit: TimeLimitEnd,
}

impl TrainRun {
    /// Whether the run is one of `profile = "as-run"`: it read the scene graph at episode ends
    /// the authors' way, which every task's profile does (and the head's constants do not); or
    /// it is SAC, which reads no graph, oracle or rule, with the profile's time limit on its
    /// task (Lunar Lander's head SAC runs are the profile's: issue 33 reuses them).
    pub fn ran_as_run(&self) -> bool {
        let config = &self.summary.config;
        config.graph_at_episode_end == GraphAtEpisodeEnd::Reset
            || (self.key.method == EvaluativeMethod::Sac.to_string()
                && config.time_limit == time_limit_as_run(self.key.task))
    }
}

/// One row of `alignment.csv`: the belief after a query.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct AlignmentRow {
    pub query: u32,
    pub alignment: f64,
    pub alignment_of_mean: f64,
}

/// `summary.json` of a `prefs` run.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct PrefsSummary {
    pub task: String,
    pub method: String,
    pub seed: u64,
    pub queries: u32,
    pub final_alignment: f64,
    #[serde(default)]
    pub mean_segment_length: Option<f64>,
    #[serde(default)]
    pub belief_update_ms_median: Option<f64>,
}

/// Where a run sits in the grid. Task and method come from the directory names, which the
/// runner chose, so that grouping does not depend on how a child spells its own method.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RunKey {
    pub task: Task,
    pub method: String,
    pub seed: u64,
}

/// A finished `train` run.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainRun {
    pub key: RunKey,
    pub episodes: Vec<EpisodeRow>,
    pub summary: TrainSummary,
}

/// A finished `prefs` run.
#[derive(Clone, Debug, PartialEq)]
pub struct PrefsRun {
    pub key: RunKey,
    pub alignment: Vec<AlignmentRow>,
    pub summary: PrefsSummary,
}

/// The directory of one run in a grid.
pub fn run_dir(root: &Path, task: Task, method: &str, seed: u64) -> PathBuf {
    root.join(task.id())
        .join(method)
        .join(format!("seed{seed}"))
}

/// Whether `dir` holds a finished run.
pub fn is_finished(dir: &Path) -> bool {
    dir.join(SUMMARY_FILE).is_file()
}

fn read_csv<T: for<'de> Deserialize<'de>>(path: &Path) -> anyhow::Result<Vec<T>> {
    let mut reader =
        csv::Reader::from_path(path).with_context(|| format!("opening {}", path.display()))?;
    reader
        .deserialize()
        .collect::<Result<Vec<T>, _>>()
        .with_context(|| format!("reading {}", path.display()))
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> anyhow::Result<T> {
    let text = fs::read_to_string(path).with_context(|| format!("opening {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("reading {}", path.display()))
}

/// Reads just `summary.json` of a finished `train` run.
pub fn read_train_summary(dir: &Path) -> anyhow::Result<TrainSummary> {
    read_json(&dir.join(SUMMARY_FILE))
}

/// Reads `metrics.csv` and `summary.json` of a finished `train` run.
pub fn read_train_run(key: RunKey, dir: &Path) -> anyhow::Result<TrainRun> {
    Ok(TrainRun {
        key,
        episodes: read_csv(&dir.join("metrics.csv"))?,
        summary: read_json(&dir.join(SUMMARY_FILE))?,
    })
}

/// Reads `alignment.csv` and `summary.json` of a finished `prefs` run.
pub fn read_prefs_run(key: RunKey, dir: &Path) -> anyhow::Result<PrefsRun> {
    Ok(PrefsRun {
        key,
        alignment: read_csv(&dir.join("alignment.csv"))?,
        summary: read_json(&dir.join(SUMMARY_FILE))?,
    })
}

/// Every finished run under `root` (`<task>/<method>/seed<S>/` with a summary), sorted by key.
/// Directories that do not fit the layout (an unknown task, `seedX`) are not runs and are passed
/// over; a run that is finished but unreadable is an error, since a figure silently missing a
/// seed would mislead.
pub fn finished_runs(root: &Path) -> anyhow::Result<Vec<(RunKey, PathBuf)>> {
    let mut runs = Vec::new();
    for task_entry in subdirs(root)? {
        let Some(task) = name_of(&task_entry).and_then(|n| n.parse::<Task>().ok()) else {
            continue;
        };
        for method_dir in subdirs(&task_entry)? {
            let Some(method) = name_of(&method_dir) else {
                continue;
            };
            for seed_dir in subdirs(&method_dir)? {
                let seed = name_of(&seed_dir)
                    .and_then(|n| n.strip_prefix("seed").and_then(|s| s.parse::<u64>().ok()));
                if let Some(seed) = seed.filter(|_| is_finished(&seed_dir)) {
                    let key = RunKey {
                        task,
                        method: method.clone(),
                        seed,
                    };
                    runs.push((key, seed_dir));
                }
            }
        }
    }
    runs.sort();
    Ok(runs)
}

/// All finished `train` runs under `root`.
pub fn load_train_runs(root: &Path) -> anyhow::Result<Vec<TrainRun>> {
    finished_runs(root)?
        .into_iter()
        .map(|(key, dir)| read_train_run(key, &dir))
        .collect()
}

/// All finished `prefs` runs under `root`.
pub fn load_prefs_runs(root: &Path) -> anyhow::Result<Vec<PrefsRun>> {
    finished_runs(root)?
        .into_iter()
        .map(|(key, dir)| read_prefs_run(key, &dir))
        .collect()
}

/// The finished runs of a robustness grid: `train` runs (`<method>-err<E>`) and `prefs` runs
/// (`<method>-beta<B>`, `<method>-rational`), each read as its kind.
pub fn load_robustness_runs(root: &Path) -> anyhow::Result<(Vec<TrainRun>, Vec<PrefsRun>)> {
    use super::robustness::{Level, parse_label};
    let (mut train, mut prefs) = (Vec::new(), Vec::new());
    for (key, dir) in finished_runs(root)? {
        match parse_label(&key.method) {
            Some((_, Level::Error(_))) => train.push(read_train_run(key, &dir)?),
            Some((_, Level::Beta(_))) => prefs.push(read_prefs_run(key, &dir)?),
            None => {}
        }
    }
    Ok((train, prefs))
}

fn subdirs(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for entry in fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let path = entry?.path();
        if path.is_dir() {
            out.push(path);
        }
    }
    Ok(out)
}

fn name_of(path: &Path) -> Option<String> {
    path.file_name()?.to_str().map(str::to_owned)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(config: &str) -> TrainSummary {
        serde_json::from_str(&format!(
            r#"{{"task": "placing", "method": "dref-authors", "seed": 0, "steps": 10,
                "cumulative_return": 0.0, "feedback_count": 1, "feedback_fraction": 0.1,
                "final_mean_return": 0.0{config}}}"#
        ))
        .unwrap()
    }

    #[test]
    fn a_run_of_the_as_run_profile_is_told_by_its_graph_at_episode_end() {
        let run = |config: &str| TrainRun {
            key: RunKey {
                task: Task::Placing,
                method: "dref-authors".into(),
                seed: 0,
            },
            episodes: Vec::new(),
            summary: summary(config),
        };
        assert!(run(r#", "config": {"graph_at_episode_end": "reset", "seed": 0}"#).ran_as_run());
        assert!(!run(r#", "config": {"graph_at_episode_end": "step"}"#).ran_as_run());
        // Runs written before the setting existed, or without a config, ran the head's way.
        assert!(!run(r#", "config": {"task": "placing"}"#).ran_as_run());
        assert!(!run("").ran_as_run());
    }

    #[test]
    fn a_sac_run_is_the_profiles_where_its_time_limit_is() {
        let sac = |task: Task, config: &str| TrainRun {
            key: RunKey {
                task,
                method: "sac".into(),
                seed: 0,
            },
            episodes: Vec::new(),
            summary: summary(config),
        };
        let head = r#", "config": {"graph_at_episode_end": "step", "time_limit": "truncation"}"#;
        // Lunar Lander's profile keeps Gymnasium's truncation: the head's SAC run is its run,
        // and so is one written before either setting existed.
        assert!(sac(Task::LunarLander, head).ran_as_run());
        assert!(sac(Task::LunarLander, r#", "config": {}"#).ran_as_run());
        // Placing's and Reaching's store robosuite's limit as terminal: the head's run is not.
        assert!(!sac(Task::Placing, head).ran_as_run());
        assert!(!sac(Task::Reaching, head).ran_as_run());
        assert!(sac(Task::Reaching, r#", "config": {"time_limit": "terminal"}"#).ran_as_run());
        // Only SAC reads nothing else of the profile.
        let ef = TrainRun {
            key: RunKey {
                task: Task::LunarLander,
                method: "ef-100".into(),
                seed: 0,
            },
            ..sac(Task::LunarLander, head)
        };
        assert!(!ef.ran_as_run());
    }
}
