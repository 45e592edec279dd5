//! Aggregation on hand-made runs whose means and standard errors can be checked by hand.

use super::*;
use crate::report::run_files::{
    AlignmentRow, EpisodeRow, PrefsRun, PrefsSummary, RunKey, TrainRun, TrainSummary,
};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9
}

/// A train run whose episodes end at the given (step, cumulative reward) points.
fn train_run(task: Task, method: &str, seed: u64, steps: u64, ends: &[(u64, f64)]) -> TrainRun {
    let episodes = ends
        .iter()
        .enumerate()
        .map(|(i, &(step, cum))| EpisodeRow {
            step,
            episode: i as u64,
            episode_return: 0.0,
            length: None,
            outcome: None,
            cumulative_return: cum,
            feedback_count: 0,
            feedback_fraction: 0.0,
            steps_since_query: None,
            longest_flood: None,
        })
        .collect();
    let final_cum = ends.last().map_or(0.0, |e| e.1);
    TrainRun {
        key: RunKey {
            task,
            method: method.into(),
            seed,
        },
        episodes,
        summary: TrainSummary {
            task: task.id().into(),
            method: method.into(),
            seed,
            steps,
            cumulative_return: final_cum,
            feedback_count: 0,
            feedback_fraction: 0.05 * (seed + 1) as f64,
            final_mean_return: 0.0,
            wall_seconds: None,
            updates_per_second: None,
            longest_flood_after_2k: None,
            config: Default::default(),
        },
    }
}

fn prefs_run(method: &str, seed: u64, alignments: &[f64]) -> PrefsRun {
    PrefsRun {
        key: RunKey {
            task: Task::Reaching,
            method: method.into(),
            seed,
        },
        alignment: alignments
            .iter()
            .enumerate()
            .map(|(i, &a)| AlignmentRow {
                query: i as u32 + 1,
                alignment: a,
                alignment_of_mean: a,
            })
            .collect(),
        summary: PrefsSummary {
            task: "reaching".into(),
            method: method.into(),
            seed,
            queries: alignments.len() as u32,
            final_alignment: *alignments.last().unwrap(),
            mean_segment_length: Some(10.0 + seed as f64),
            belief_update_ms_median: None,
        },
    }
}

#[test]
fn report_seed_curve_starts_at_zero_and_is_sorted() {
    let run = train_run(Task::Reaching, "sac", 0, 100, &[(60, 5.0), (30, 2.0)]);
    assert_eq!(seed_curve(&run), vec![(0.0, 0.0), (30.0, 2.0), (60.0, 5.0)]);
}

#[test]
fn report_fig3_interpolates_each_seed_onto_the_common_grid() {
    // Seed 0 ends episodes at 50 and 100, seed 1 at 40 and 100. On the grid [0, 50, 100]:
    //   x = 50:  seed 0 = 10, seed 1 = 8 + (20 - 8) * 10/60 = 10  -> mean 10, se 0
    //   x = 100: 30 and 20 -> mean 25, sample sd sqrt(50), se sqrt(50)/sqrt(2) = 5
    let runs = [
        train_run(Task::Reaching, "dref", 0, 100, &[(50, 10.0), (100, 30.0)]),
        train_run(Task::Reaching, "dref", 1, 100, &[(40, 8.0), (100, 20.0)]),
    ];
    let tasks = aggregate_fig3(&runs, 3);
    assert_eq!(tasks.len(), 1);
    let m = &tasks[0].methods[0];
    assert_eq!(m.curve.x, vec![0.0, 50.0, 100.0]);
    assert!(close(m.curve.mean[0], 0.0) && close(m.curve.se[0], 0.0));
    assert!(close(m.curve.mean[1], 10.0) && close(m.curve.se[1], 0.0));
    assert!(close(m.curve.mean[2], 25.0) && close(m.curve.se[2], 5.0));
    assert_eq!(m.curve.n, vec![2, 2, 2]);
    assert!(close(m.final_return.mean, 25.0) && close(m.final_return.se, 5.0));
    // Feedback fractions 0.05 and 0.10 -> 7.5 % on average, se 2.5 %.
    assert!(close(m.feedback_pct.mean, 7.5) && close(m.feedback_pct.se, 2.5));
    assert_eq!(m.steps, 100);
}

#[test]
fn report_fig3_grid_ends_at_the_shortest_seed_and_holds_flat_after_the_last_episode() {
    let runs = [
        train_run(Task::Placing, "sac", 0, 200, &[(100, 4.0)]),
        train_run(Task::Placing, "sac", 1, 100, &[(50, 2.0)]),
    ];
    let m = &aggregate_fig3(&runs, 2)[0].methods[0];
    assert_eq!(m.curve.x, vec![0.0, 100.0]);
    // Seed 1 finished its last episode at 50: its cumulative reward stays 2 until 100.
    assert!(close(m.curve.mean[1], 3.0));
}

#[test]
fn report_fig3_orders_panels_and_legend_like_the_paper() {
    let one = &[(10, 1.0)];
    let runs = [
        train_run(Task::Reaching, "sac", 0, 10, one),
        train_run(Task::Reaching, "ef-1.6", 0, 10, one),
        train_run(Task::Reaching, "dref", 0, 10, one),
        train_run(Task::LunarLander, "ef-100", 0, 10, one),
        train_run(Task::Reaching, "ef-50", 0, 10, one),
    ];
    let tasks = aggregate_fig3(&runs, 2);
    let order: Vec<(Task, Vec<&str>)> = tasks
        .iter()
        .map(|t| {
            let ms = t.methods.iter().map(|m| m.method.as_str()).collect();
            (t.task, ms)
        })
        .collect();
    assert_eq!(
        order,
        vec![
            (Task::LunarLander, vec!["ef-100"]),
            (Task::Reaching, vec!["dref", "ef-50", "sac", "ef-1.6"]),
        ]
    );
}

#[test]
fn report_fig5_averages_per_query_over_the_seeds_that_reached_it() {
    let runs = [
        prefs_run("drpl", 0, &[0.2, 0.6, 0.8]),
        prefs_run("drpl", 1, &[0.4, 0.8]),
        prefs_run("full", 0, &[0.1, 0.1]),
    ];
    let tasks = aggregate_fig5(&runs);
    let drpl = &tasks[0].methods[0];
    assert_eq!(drpl.method, "drpl");
    assert_eq!(drpl.curve.x, vec![1.0, 2.0, 3.0]);
    assert!(close(drpl.curve.mean[0], 0.3) && close(drpl.curve.se[0], 0.1));
    assert!(close(drpl.curve.mean[1], 0.7) && close(drpl.curve.se[1], 0.1));
    assert!(close(drpl.curve.mean[2], 0.8) && close(drpl.curve.se[2], 0.0));
    assert_eq!(drpl.curve.n, vec![2, 2, 1]);
    // Final alignments 0.8 and 0.8; segment lengths 10 and 11.
    assert!(close(drpl.final_alignment.mean, 0.8) && close(drpl.final_alignment.se, 0.0));
    assert!(close(drpl.segment_length.mean, 10.5));
    assert_eq!(drpl.finals_by_seed, vec![(0, 0.8), (1, 0.8)]);
    assert_eq!(tasks[0].methods[1].method, "full");
    assert_eq!(tasks[0].methods[1].finals_by_seed, vec![(0, 0.1)]);
}

#[test]
fn report_dref_rate_is_the_mean_over_drefs_seeds_on_that_task() {
    let one = &[(10, 1.0)];
    let runs = [
        train_run(Task::Reaching, "dref", 0, 10, one), // 5 %
        train_run(Task::Reaching, "dref", 1, 10, one), // 10 %
        train_run(Task::Reaching, "sac", 2, 10, one),
        train_run(Task::Placing, "dref", 3, 10, one), // 20 %
    ];
    assert!(close(
        dref_feedback_pct(&runs, Task::Reaching).unwrap(),
        7.5
    ));
    assert!(close(
        dref_feedback_pct(&runs, Task::Placing).unwrap(),
        20.0
    ));
    assert_eq!(dref_feedback_pct(&runs, Task::LunarLander), None);
}
