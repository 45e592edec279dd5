//! Table formatting on hand-made aggregates.

use super::*;
use crate::report::aggregate::{Curve, Fig3Method as Fig3Row, Fig5Method as Fig5Row};
use crate::report::stats::mean_se;
use crate::sim::Task;

fn ms(mean: f64, se: f64, n: usize) -> MeanSe {
    MeanSe { mean, se, n }
}

fn fig3_row(method: &str, final_return: MeanSe, feedback: MeanSe) -> Fig3Row {
    Fig3Row {
        method: method.into(),
        curve: Curve::default(),
        final_return,
        finals: Vec::new(),
        feedback_pct: feedback,
        steps: 150_000,
        seeds_learned: 0,
        frozen_pct: ms(0.0, 0.0, final_return.n),
        longest_flood_after_2k: (0, true),
        runs: Vec::new(),
    }
}

#[test]
fn report_numbers_are_formatted_like_the_paper() {
    assert_eq!(fmt_reward(ms(34_123.0, 1_260.0, 5), true), "34.1k ± 1.3k");
    assert_eq!(fmt_reward(ms(-6_000.0, 40.0, 5), true), "-6.0k ± 0.0k");
    assert_eq!(fmt_reward(ms(812.4, 31.6, 5), true), "0.8k ± 0.0k");
    assert_eq!(fmt_reward(ms(812.4, 31.6, 5), false), "812 ± 32");
    assert_eq!(fmt_reward(ms(f64::NAN, f64::NAN, 0), false), "–");
    assert_eq!(fmt_pct(ms(6.24, 0.31, 5)), "6.2 ± 0.3 %");
    assert_eq!(fmt_steps(150_000), "150k");
    assert_eq!(fmt_steps(1_500), "1500");
    assert_eq!(fmt_ratio(Some(-2.0), Some(4.0)), "-0.50");
    assert_eq!(
        fmt_ratio(Some(-2.0), Some(-4.0)),
        "–",
        "no ratio to a negative sum"
    );
    assert_eq!(fmt_ratio(None, Some(4.0)), "–");
}

#[test]
fn report_fig3_table_puts_the_papers_values_beside_ours() {
    // At 6.24 %, DREF's EF row named to one decimal (EF-6.2) is still "at its rate".
    let mut dref = fig3_row("dref", ms(30_000.0, 1_000.0, 5), ms(6.24, 0.4, 5));
    dref.finals = vec![31e3, 29e3, 30e3, 32e3, 28e3];
    let mut matched = fig3_row("ef-6.2", ms(-1_000.0, 2_000.0, 4), ms(6.1, 0.1, 4));
    matched.finals = vec![-1e3, -3e3, 1e3, 0.0];
    let tasks = [Fig3Task {
        task: Task::LunarLander,
        methods: vec![
            dref,
            fig3_row("ef-100", ms(25_000.0, 1_000.0, 5), ms(100.0, 0.0, 5)),
            fig3_row("sac", ms(860.0, 500.0, 5), ms(0.0, 0.0, 5)),
            matched,
        ],
    }];
    let text = fig3_table(&tasks, false);
    let expected = "\
## Lunar-Lander: 150k steps (paper: 150k)

| Method | Cumulative reward | Feedback | Seeds | Seeds that learn | Frozen | Longest flood after 2k | Ratio to EF-100% | Paper's ratio | Paper |
|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|
| DREF | 30.0k ± 1.0k | 6.2 ± 0.4 % | 5 | 0 | 0.0 ± 0.0 % | 0 | 1.20 | 1.17 | 34.1k (6.3 %) |
| EF-100% | 25.0k ± 1.0k | 100.0 ± 0.0 % | 5 | 0 | – | – | 1.00 | 1.00 | 29.1k |
| EF-50% | – | – | 0 | – | – | – | – | 0.83 | 24.2k |
| EF-25% | – | – | 0 | – | – | – | – | 0.64 | 18.7k |
| SAC | 0.9k ± 0.5k | 0.0 ± 0.0 % | 5 | 0 | – | – | 0.03 | 0.60 | 17.6k |
| EF-6.2% (DREF's rate) | -1.0k ± 2.0k | 6.1 ± 0.1 % | 4 | 0 | – | – | -0.04 | -0.21 | -6.0k |

DREF above EF-6.2% (its rate): one-sided exact Mann-Whitney U = 20.0 over 5 and 4 seeds, p = 0.0079.
";
    assert!(text.starts_with("# Figure 3"), "{text}");
    assert!(
        text.ends_with(expected),
        "got:\n{text}\nwanted the end:\n{expected}"
    );
}

#[test]
fn report_an_ef_row_at_a_rate_is_named_after_the_rule_whose_rate_it_is() {
    let row = |method: &str, rate: f64| {
        let mut r = fig3_row(method, ms(1e3, 1e2, 5), ms(rate, 0.0, 5));
        r.finals = vec![1e3; 5];
        r
    };
    let text = fig3_table(
        &[Fig3Task {
            task: Task::LunarLander,
            methods: vec![
                row("dref", 9.06),
                row("dref-authors", 2.12),
                row("ef-9.06", 9.06),
                row("ef-2.12", 2.12),
                row("ef-10.31", 10.31),
            ],
        }],
        false,
    );
    for line in [
        "| EF-9.06% (DREF's rate) |",
        "| EF-2.12% (the authors' DREF's rate) |",
        "| EF-10.31% (a DREF's rate not in this table) |",
    ] {
        assert!(text.contains(line), "no {line} in:\n{text}");
    }
    assert!(
        text.contains("DREF (authors' code) above EF-2.12% (its rate)"),
        "{text}"
    );
}

#[test]
fn report_fig3_table_lists_each_dref_runs_pacing() {
    use crate::report::aggregate::RunPacing;
    let mut dref = fig3_row("dref", ms(9.0, 1.0, 2), ms(5.0, 0.0, 2));
    dref.runs = vec![
        RunPacing {
            seed: 0,
            learned: true,
            feedback_pct: 5.02,
            frozen_pct: 0.0,
            longest_flood_after_2k: (2, true),
        },
        RunPacing {
            seed: 3,
            learned: false,
            feedback_pct: 2.61,
            frozen_pct: 41.25,
            longest_flood_after_2k: (140, false),
        },
    ];
    let mut sac = fig3_row("sac", ms(5.0, 1.0, 2), ms(0.0, 0.0, 2));
    sac.runs = dref.runs.clone();
    let text = fig3_table(
        &[Fig3Task {
            task: Task::Placing,
            methods: vec![dref, sac],
        }],
        false,
    );
    let expected = "\
DREF, per run:

| seed | learns | feedback | frozen | longest flood after 2k |
|---|---|---:|---:|---:|
| 0 | yes | 5.02 % | 0.0 % | 2 |
| 3 | no | 2.61 % | 41.2 % | >= 140 |
";
    assert!(text.ends_with(expected), "{text}");
    assert!(!text.contains("SAC, per run"), "{text}");
}

#[test]
fn report_fig3_table_names_a_missing_matched_baseline_and_shows_step_ranges() {
    let mut short = fig3_row("sac", ms(5.0, 1.0, 2), ms(0.0, 0.0, 2));
    short.steps = 2_000;
    let mut long = fig3_row("dref", ms(9.0, 1.0, 2), ms(1.6, 0.1, 2));
    long.steps = 100_000;
    let text = fig3_table(
        &[Fig3Task {
            task: Task::Reaching,
            methods: vec![long, short],
        }],
        false,
    );
    assert!(
        text.contains("## Reaching-Sim: 2k–100k steps (paper: 100k)"),
        "{text}"
    );
    assert!(
        text.contains("| EF at DREF's rate | – | – | 0 | – | – | – | – | 0.89 | 10.2k |"),
        "{text}"
    );
    assert!(
        text.contains(
            "| DREF | 9 ± 1 | 1.6 ± 0.1 % | 2 | 0 | 0.0 ± 0.0 % | 0 | – | 1.00 | 11.4k (1.6 %) |"
        ),
        "{text}"
    );
}

#[test]
fn report_fig3_table_of_the_runs_as_run_reads_them_against_the_authors_own_runs() {
    let rows = || {
        vec![
            fig3_row("dref-authors", ms(9.0, 1.0, 2), ms(1.6, 0.1, 2)),
            fig3_row("ef-100", ms(10.0, 1.0, 2), ms(100.0, 0.0, 2)),
        ]
    };
    let plain = fig3_table(
        &[Fig3Task {
            task: Task::Reaching,
            methods: rows(),
        }],
        false,
    );
    assert!(!plain.contains("all-runs"), "{plain}");
    let text = fig3_table(
        &[Fig3Task {
            task: Task::Reaching,
            methods: rows(),
        }],
        true,
    );
    assert!(
        text.contains(
            "| Paper's ratio | Authors' plotted ratio | Authors' all-runs ratio | Paper |"
        ),
        "{text}"
    );
    // Reaching's DREF: 1.00 as published, 0.815 over all 33 finished runs of its batches.
    assert!(
        text.contains("| 0.90 | 1.00 | 0.99 ± 0.03 | 0.81 ± 0.03 | 11.4k (1.6 %) |"),
        "{text}"
    );
    // A row the grid has not run still shows the authors' numbers (SAC).
    assert!(
        text.contains(
            "| SAC | – | – | 0 | – | – | – | – | 0.54 | 0.54 ± 0.04 | 0.58 ± 0.03 | 6.2k |"
        ),
        "{text}"
    );
}

#[test]
fn report_fig5_table_lists_both_alignments_and_segment_length() {
    let row = |method: &str, a: f64, len: f64| Fig5Row {
        method: method.into(),
        curve: Curve {
            x: vec![1.0, 40.0],
            ..Curve::default()
        },
        final_alignment: ms(a, 0.02, 5),
        finals_by_seed: Vec::new(),
        final_alignment_of_mean: ms(a + 0.05, 0.01, 5),
        segment_length: ms(len, 0.5, 5),
    };
    let text = fig5_table(&[Fig5Task {
        task: Task::Placing,
        methods: vec![row("drpl", 0.85, 12.0), row("fragment", 0.41, 12.0)],
    }]);
    let expected = "\
## Placing-Sim: 40 queries

| Method | Final alignment | Alignment of mean | Mean segment length | Seeds |
|---|---:|---:|---:|---:|
| DRPL | 0.850 ± 0.020 | 0.900 ± 0.010 | 12.0 ± 0.5 | 5 |
| Random fragment | 0.410 ± 0.020 | 0.460 ± 0.010 | 12.0 ± 0.5 | 5 |
";
    assert!(text.ends_with(expected), "got:\n{text}");
}

fn fig5_row(method: &str, finals_by_seed: &[(u64, f64)]) -> Fig5Row {
    let finals: Vec<f64> = finals_by_seed.iter().map(|&(_, a)| a).collect();
    Fig5Row {
        method: method.into(),
        curve: Curve {
            x: vec![1.0, 40.0],
            ..Curve::default()
        },
        final_alignment: mean_se(&finals),
        finals_by_seed: finals_by_seed.to_vec(),
        final_alignment_of_mean: ms(0.5, 0.01, finals.len()),
        segment_length: ms(10.0, 0.5, finals.len()),
    }
}

/// DRPL has seeds 0-5, the baseline 1-6 (listed out of order): only seeds 1-5 pair, each with
/// its own seed. Differences +0.05, +0.04, +0.03, +0.02, -0.045: ranks 5, 3, 2, 1 above and 4
/// below, R+ = 11, exact one-sided p = P(R+ >= 11 | n = 5) = 7/32. Paired by position instead,
/// DRPL would win 1 of 6.
#[test]
fn report_fig5_paired_test_pairs_by_seed_over_the_seeds_both_rows_have() {
    let drpl = fig5_row(
        "drpl",
        &[
            (0, 0.50),
            (1, 0.60),
            (2, 0.70),
            (3, 0.80),
            (4, 0.90),
            (5, 0.95),
        ],
    );
    let ss = fig5_row(
        "drpl-ss",
        &[
            (6, 0.10),
            (3, 0.77),
            (1, 0.55),
            (5, 0.995),
            (2, 0.66),
            (4, 0.88),
        ],
    );
    let line = fig5_paired_line(&drpl, &ss).unwrap();
    assert_eq!(
        line,
        "DRPL above DRPL-SS: one-sided paired Wilcoxon signed-rank over 5 seeds (paired by seed), \
         mean difference +0.019 ± 0.017, wins 4 of 5, p = 0.219."
    );
    // The other way round: the same pairs, the other tail, P(R+ >= 4 | n = 5) = 27/32.
    let back = fig5_paired_line(&ss, &drpl).unwrap();
    assert!(
        back.starts_with("DRPL-SS above DRPL: one-sided paired Wilcoxon signed-rank over 5 seeds"),
        "{back}"
    );
    assert!(
        back.ends_with("mean difference -0.019 ± 0.017, wins 1 of 5, p = 0.844."),
        "{back}"
    );
    // No seed in common: no test.
    let elsewhere = fig5_row("full", &[(7, 0.1), (8, 0.2)]);
    assert_eq!(fig5_paired_line(&drpl, &elsewhere), None);
}

/// 20 seeds all above: p = 2^-20, as scipy's `wilcoxon(d, alternative="greater")` gives
/// (docs/results/fig5/ablations/paired.md: 9.5e-07); all below: p = 1.
#[test]
fn report_fig5_paired_test_reads_the_direction_of_the_difference() {
    let hi: Vec<(u64, f64)> = (0..20).map(|s| (s, 0.9 + 0.001 * s as f64)).collect();
    let lo: Vec<(u64, f64)> = (0..20).map(|s| (s, 0.5 - 0.01 * s as f64)).collect();
    let (mi, full) = (fig5_row("drpl-mi", &hi), fig5_row("full", &lo));
    let up = fig5_paired_line(&mi, &full).unwrap();
    assert!(
        up.starts_with(
            "DRPL-MI above Full trajectory: one-sided paired Wilcoxon signed-rank over 20 seeds"
        ),
        "{up}"
    );
    assert!(up.ends_with("wins 20 of 20, p = 9.5e-7."), "{up}");
    let down = fig5_paired_line(&full, &mi).unwrap();
    assert!(down.ends_with("wins 0 of 20, p = 1.000."), "{down}");
}

/// The table tests DRPL and DRPL-MI against each baseline it has, and DRPL-MI against DRPL; a
/// missing row gets no line, and a baseline is never tested against DRPL.
#[test]
fn report_fig5_table_lists_the_paired_tests_of_the_rows_it_has() {
    let seeds = |level: f64| -> Vec<(u64, f64)> {
        // Distinct differences (no ties): (level - other) * (1 + s / 1000).
        (0..6)
            .map(|s| (s, level * (1.0 + 0.001 * s as f64)))
            .collect()
    };
    let text = fig5_table(&[Fig5Task {
        task: Task::Reaching,
        methods: vec![
            fig5_row("drpl", &seeds(0.8)),
            fig5_row("drpl-ss", &seeds(0.7)),
            fig5_row("full", &seeds(0.6)),
            fig5_row("drpl-mi", &seeds(0.9)),
        ],
    }]);
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("- "))
        .map(|l| l.split(':').next().unwrap())
        .collect();
    assert_eq!(
        lines,
        [
            "- DRPL above DRPL-SS",
            "- DRPL above Full trajectory",
            "- DRPL-MI above DRPL-SS",
            "- DRPL-MI above Full trajectory",
            "- DRPL-MI above DRPL",
        ],
        "{text}"
    );
    assert!(
        text.contains("| DRPL-MI (ours: mutual-information pick) | 0.902 ± "),
        "{text}"
    );
    // Every row 0.1 above the next on every seed: 6 of 6, p = 1/64.
    assert_eq!(text.matches("wins 6 of 6, p = 0.016.").count(), 5, "{text}");
}
