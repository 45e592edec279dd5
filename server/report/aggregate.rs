//! Aggregation across seeds, pure: runs in, means and standard errors out.
//!
//! Figure 3: each seed's cumulative reward is known only where an episode ended, and episodes
//! end at different steps in different seeds, so each seed's curve is interpolated onto one
//! common step grid before averaging. Figure 5: every seed answers the same numbered queries,
//! so seeds are averaged per query index.

use std::collections::BTreeMap;

use serde::Serialize;

use super::methods::{order_key, task_rank};
use super::run_files::{PrefsRun, TrainRun};
use super::stats::{MeanSe, interpolate, linspace, mean_se};
use crate::guidance::ask_pacing::{AskPacing, frozen_share};
use crate::sim::{Outcome, Task};

/// Points on the common step grid of a Figure 3 curve (every 1 % of training).
pub const FIG3_GRID_POINTS: usize = 101;

/// A mean curve over seeds with its standard error at each x.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Curve {
    pub x: Vec<f64>,
    pub mean: Vec<f64>,
    pub se: Vec<f64>,
    /// Seeds behind each point.
    pub n: Vec<usize>,
}

/// One method's Figure 3 result on one task.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fig3Method {
    pub method: String,
    pub curve: Curve,
    /// Cumulative reward at the end of training (from each seed's summary).
    pub final_return: MeanSe,
    /// The same per seed, in seed-directory order (for rank tests between methods).
    pub finals: Vec<f64>,
    /// Feedback as a percentage of environment steps.
    pub feedback_pct: MeanSe,
    /// The shortest run among the seeds: where the common grid ends.
    pub steps: u64,
    /// Seeds whose last 10 episodes show the task learnt ([`learned`]).
    pub seeds_learned: usize,
    /// Per seed, the share of episodes (in %) after which the rule had been silent for 10k
    /// steps while the last 10 episodes failed ("frozen").
    pub frozen_pct: MeanSe,
    /// The longest stretch of consecutive asked steps after the first 2k, over the seeds, and
    /// whether it is exact (else a lower bound read from whole episodes of older runs).
    pub longest_flood_after_2k: (u64, bool),
    /// The same per run, with its seed and whether it learnt.
    pub runs: Vec<RunPacing>,
}

/// One run's pacing, for the per-run table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunPacing {
    pub seed: u64,
    pub learned: bool,
    pub feedback_pct: f64,
    pub frozen_pct: f64,
    pub longest_flood_after_2k: (u64, bool),
}

/// Episodes behind "learnt": the last 10, as the bar reads.
pub const LEARNED_EPISODES: usize = 10;

/// Whether a run learnt its task: 8 or more successes in its last 10 episodes on Reaching and
/// Placing, a mean return of 200 or more over them on Lunar Lander (Gymnasium's "solved").
pub fn learned(run: &TrainRun) -> bool {
    let tail = &run.episodes[run.episodes.len().saturating_sub(LEARNED_EPISODES)..];
    if tail.len() < LEARNED_EPISODES {
        return false;
    }
    match run.key.task {
        Task::LunarLander => {
            tail.iter().map(|e| e.episode_return).sum::<f64>() / tail.len() as f64 >= 200.0
        }
        Task::Reaching | Task::Placing => {
            tail.iter()
                .filter(|e| e.outcome == Some(Outcome::Success))
                .count()
                >= 8
        }
    }
}

/// Per episode: steps since the rule last asked, at its end. Runs written before the column
/// existed give a lower bound: the steps since the end of the last episode in which the count
/// of answers grew.
fn steps_since_query(run: &TrainRun) -> Vec<u64> {
    let mut last_growth_end: Option<u64> = None;
    let mut previous = 0u64;
    run.episodes
        .iter()
        .map(|e| {
            if e.feedback_count > previous {
                last_growth_end = Some(e.step);
            }
            previous = e.feedback_count;
            e.steps_since_query
                .unwrap_or_else(|| e.step - last_growth_end.unwrap_or(0))
        })
        .collect()
}

/// The share of a run's episodes (in %) after which its rule was frozen.
pub fn frozen_pct(run: &TrainRun) -> f64 {
    let episodes: Vec<(u64, bool)> = steps_since_query(run)
        .into_iter()
        .zip(&run.episodes)
        .map(|(since, e)| (since, e.outcome == Some(Outcome::Success)))
        .collect();
    100.0 * frozen_share(&episodes)
}

/// A run's longest stretch of consecutive asked steps after its first 2k, and whether it is
/// exact: from `summary.json` where the run measured it, else a lower bound from consecutive
/// episodes asked on every one of their steps.
pub fn longest_flood_after_2k(run: &TrainRun) -> (u64, bool) {
    if let Some(n) = run.summary.longest_flood_after_2k {
        return (n, true);
    }
    let (mut longest, mut stretch, mut previous) = (0u64, 0u64, (0u64, 0u64));
    for e in &run.episodes {
        let (steps, asked) = (e.step - previous.0, e.feedback_count - previous.1);
        stretch = if steps > 0 && asked == steps {
            stretch + steps
        } else {
            0
        };
        if e.step > AskPacing::SETTLED_AFTER {
            longest = longest.max(stretch.min(e.step - AskPacing::SETTLED_AFTER));
        }
        previous = (e.step, e.feedback_count);
    }
    (longest, false)
}

/// One Figure 3 panel: every method that has a finished run on the task, in legend order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fig3Task {
    pub task: Task,
    pub methods: Vec<Fig3Method>,
}

/// One method's Figure 5 result on one task.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fig5Method {
    pub method: String,
    /// x is the query index.
    pub curve: Curve,
    pub final_alignment: MeanSe,
    /// The same per run, as (seed, final alignment): what the paired tests between methods
    /// pair by seed (each seed has its own true reward and trajectories, the same for every
    /// method).
    pub finals_by_seed: Vec<(u64, f64)>,
    /// cos(posterior mean, theta_true) after the last query: APReL's `cosine_similarity`.
    pub final_alignment_of_mean: MeanSe,
    pub segment_length: MeanSe,
}

/// One Figure 5 panel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fig5Task {
    pub task: Task,
    pub methods: Vec<Fig5Method>,
}

/// A seed's cumulative reward as (step, value) points, starting from (0, 0) before any episode.
pub fn seed_curve(run: &TrainRun) -> Vec<(f64, f64)> {
    let mut points = Vec::with_capacity(run.episodes.len() + 1);
    points.push((0.0, 0.0));
    points.extend(
        run.episodes
            .iter()
            .map(|e| (e.step as f64, e.cumulative_return)),
    );
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// Mean and standard error over `curves` of each curve interpolated at every x of `grid`.
pub fn mean_on_grid(curves: &[Vec<(f64, f64)>], grid: &[f64]) -> Curve {
    let mut out = Curve {
        x: grid.to_vec(),
        ..Curve::default()
    };
    for &x in grid {
        let at_x: Vec<f64> = curves.iter().map(|c| interpolate(c, x)).collect();
        let m = mean_se(&at_x);
        out.mean.push(m.mean);
        out.se.push(m.se);
        out.n.push(m.n);
    }
    out
}

/// The seeds of one method on one task.
type MethodRuns<'a, R> = (String, Vec<&'a R>);

/// Runs grouped by task, then method, in the paper's panel and legend order.
fn grouped<R>(runs: &[R], key: impl Fn(&R) -> (Task, &str)) -> Vec<(Task, Vec<MethodRuns<'_, R>>)> {
    // Keyed by (rank, name) so that iteration order is the paper's order.
    type ByMethod<'a, R> = BTreeMap<(usize, String), Vec<&'a R>>;
    let mut by_task: BTreeMap<(usize, Task), ByMethod<'_, R>> = BTreeMap::new();
    for run in runs {
        let (task, method) = key(run);
        by_task
            .entry((task_rank(task), task))
            .or_default()
            .entry(order_key(method))
            .or_default()
            .push(run);
    }
    by_task
        .into_iter()
        .map(|((_, task), methods)| {
            let methods = methods.into_iter().map(|((_, m), r)| (m, r)).collect();
            (task, methods)
        })
        .collect()
}

/// Figure 3's numbers: per task and method, the mean cumulative-reward curve on a grid of
/// `points` steps from 0 to the shortest seed's length, and the final values of the table.
pub fn aggregate_fig3(runs: &[TrainRun], points: usize) -> Vec<Fig3Task> {
    grouped(runs, |r| (r.key.task, r.key.method.as_str()))
        .into_iter()
        .map(|(task, methods)| Fig3Task {
            task,
            methods: methods
                .into_iter()
                .map(|(method, seeds)| {
                    let steps = seeds.iter().map(|r| r.summary.steps).min().unwrap_or(0);
                    let curves: Vec<_> = seeds.iter().map(|r| seed_curve(r)).collect();
                    let grid = linspace(0.0, steps as f64, points);
                    let finals: Vec<f64> =
                        seeds.iter().map(|r| r.summary.cumulative_return).collect();
                    let feedback: Vec<f64> = seeds
                        .iter()
                        .map(|r| 100.0 * r.summary.feedback_fraction)
                        .collect();
                    let pacing: Vec<RunPacing> = seeds
                        .iter()
                        .map(|r| RunPacing {
                            seed: r.key.seed,
                            learned: learned(r),
                            feedback_pct: 100.0 * r.summary.feedback_fraction,
                            frozen_pct: frozen_pct(r),
                            longest_flood_after_2k: longest_flood_after_2k(r),
                        })
                        .collect();
                    let frozen: Vec<f64> = pacing.iter().map(|r| r.frozen_pct).collect();
                    let longest = pacing.iter().fold((0, true), |(n, exact), r| {
                        let (m, e) = r.longest_flood_after_2k;
                        (n.max(m), exact && e)
                    });
                    Fig3Method {
                        method,
                        curve: mean_on_grid(&curves, &grid),
                        final_return: mean_se(&finals),
                        finals,
                        feedback_pct: mean_se(&feedback),
                        steps,
                        seeds_learned: pacing.iter().filter(|r| r.learned).count(),
                        frozen_pct: mean_se(&frozen),
                        longest_flood_after_2k: longest,
                        runs: pacing,
                    }
                })
                .collect(),
        })
        .collect()
}

/// Figure 5's numbers: per task and method, mean alignment and its standard error per query
/// index (over the seeds that reached that query), and the final values of the table.
pub fn aggregate_fig5(runs: &[PrefsRun]) -> Vec<Fig5Task> {
    grouped(runs, |r| (r.key.task, r.key.method.as_str()))
        .into_iter()
        .map(|(task, methods)| Fig5Task {
            task,
            methods: methods
                .into_iter()
                .map(|(method, seeds)| {
                    let mut per_query: BTreeMap<u32, Vec<f64>> = BTreeMap::new();
                    for row in seeds.iter().flat_map(|r| &r.alignment) {
                        per_query.entry(row.query).or_default().push(row.alignment);
                    }
                    let mut curve = Curve::default();
                    for (query, values) in per_query {
                        let m = mean_se(&values);
                        curve.x.push(f64::from(query));
                        curve.mean.push(m.mean);
                        curve.se.push(m.se);
                        curve.n.push(m.n);
                    }
                    let finals_by_seed: Vec<(u64, f64)> = seeds
                        .iter()
                        .map(|r| (r.key.seed, r.summary.final_alignment))
                        .collect();
                    let finals: Vec<f64> = finals_by_seed.iter().map(|&(_, a)| a).collect();
                    let finals_of_mean: Vec<f64> = seeds
                        .iter()
                        .filter_map(|r| r.alignment.last().map(|row| row.alignment_of_mean))
                        .collect();
                    let lengths: Vec<f64> = seeds
                        .iter()
                        .filter_map(|r| r.summary.mean_segment_length)
                        .collect();
                    Fig5Method {
                        method,
                        curve,
                        final_alignment: mean_se(&finals),
                        finals_by_seed,
                        final_alignment_of_mean: mean_se(&finals_of_mean),
                        segment_length: mean_se(&lengths),
                    }
                })
                .collect(),
        })
        .collect()
}

/// DREF's measured mean feedback percentage on `task` among `runs`, if it has any finished run:
/// the rate at which the grid then runs "EF at DREF's rate".
pub fn dref_feedback_pct(runs: &[TrainRun], task: Task) -> Option<f64> {
    let rates: Vec<f64> = runs
        .iter()
        .filter(|r| r.key.task == task && r.key.method == "dref")
        .map(|r| 100.0 * r.summary.feedback_fraction)
        .collect();
    (!rates.is_empty()).then(|| mean_se(&rates).mean)
}

#[cfg(test)]
#[path = "aggregate_tests.rs"]
mod tests;
