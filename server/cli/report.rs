//! `dualrep report`: reports from a server's data dir, without the server. `report study`
//! writes a human-subject study's results as `GET /api/studies/{id}/results` gives them
//! (`results.json`), its tidy table (`table.csv`, `table.parquet`: a row per participant ×
//! condition, for R or pandas), Figure 4's shape (`figure.svg`, `figure.png`: cumulative
//! reward per condition, mean ± s.e. over participants, and the survey's mean answers), and a
//! short `summary.md` with the tests.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};

use super::output::write_atomically;
use crate::export::study_table;
use crate::http::study_runs::{participant_runs, study_row};
use crate::report::plot::study::{ConditionCurve, QuestionBars, StudyPanel};
use crate::report::plot::write_figure;
use crate::store::{DB_FILE, Store};
use crate::study::StudySpec;
use crate::study::results::{StudyResults, summarise};

#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(subcommand)]
    pub what: ReportWhat,
}

#[derive(Debug, Subcommand)]
pub enum ReportWhat {
    /// A human-subject study's results, tidy table (CSV, Parquet) and figure (SVG, PNG).
    Study(StudyReportArgs),
}

#[derive(Debug, Args)]
pub struct StudyReportArgs {
    /// The server's data dir (the one `dualrep serve --data-dir` used).
    #[arg(long, default_value = "data")]
    pub data_dir: PathBuf,
    /// The study's id (`GET /api/studies` lists them).
    #[arg(long)]
    pub study: String,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: ReportArgs) -> anyhow::Result<()> {
    match args.what {
        ReportWhat::Study(args) => study(args),
    }
}

fn study(args: StudyReportArgs) -> anyhow::Result<()> {
    if !args.data_dir.join(DB_FILE).is_file() {
        bail!(
            "{} holds no dualrep database ({DB_FILE}); give the data dir of `dualrep serve`",
            args.data_dir.display()
        );
    }
    let (spec, participants, runs) = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?
        .block_on(async {
            let store = Store::open(&args.data_dir).await?;
            let (row, spec) = study_row(&store, &args.study)
                .await
                .with_context(|| format!("in {}", args.data_dir.display()))?;
            let participants = store.participants(&row.id).await?.len();
            let runs = participant_runs(&store, &row.id).await?;
            anyhow::Ok((spec, participants, runs))
        })?;
    let results = summarise(&spec, participants, &runs);
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let json = serde_json::to_string_pretty(&results)?;
    write_atomically(&out.join("results.json"), json.as_bytes())?;
    write_atomically(
        &out.join("table.csv"),
        study_table::csv(&spec, &runs).as_bytes(),
    )?;
    write_atomically(
        &out.join("table.parquet"),
        &study_table::parquet(&spec, &runs)?,
    )?;
    write_figure(
        &panels(&spec, &results),
        &out.join("figure.svg"),
        &out.join("figure.png"),
    )?;
    let summary = summary_md(&spec, &results);
    write_atomically(&out.join("summary.md"), summary.as_bytes())?;
    print!("{summary}");
    println!("wrote {}", display_files(out));
    Ok(())
}

fn display_files(out: &Path) -> String {
    [
        "results.json",
        "table.csv",
        "table.parquet",
        "figure.svg",
        "figure.png",
        "summary.md",
    ]
    .iter()
    .map(|f| out.join(f).display().to_string())
    .collect::<Vec<_>>()
    .join(", ")
}

/// The figure's two panels from the results.
pub fn panels(spec: &StudySpec, results: &StudyResults) -> Vec<StudyPanel> {
    let curves = results
        .conditions
        .iter()
        .map(|c| ConditionCurve {
            name: c.name.clone(),
            steps: c.curve.steps.clone(),
            mean: c.curve.mean.clone(),
            se: c.curve.se.clone(),
        })
        .collect();
    let questions = spec
        .survey
        .iter()
        .map(|q| QuestionBars {
            question: q.id.clone(),
            points: q.points,
            bars: results
                .conditions
                .iter()
                .map(|c| {
                    let counts = c
                        .survey
                        .get(&q.id)
                        .map(|s| s.counts.clone())
                        .unwrap_or_default();
                    let (mean, se) = likert_mean_se(&counts);
                    (c.name.clone(), mean, se)
                })
                .collect(),
        })
        .collect();
    vec![
        StudyPanel::Curves {
            title: spec.title.clone(),
            curves,
        },
        StudyPanel::Survey {
            title: "Survey".into(),
            questions,
        },
    ]
}

/// Mean and standard error of answers given as counts per scale point (1-based).
fn likert_mean_se(counts: &[usize]) -> (f64, f64) {
    let values: Vec<f64> = counts
        .iter()
        .enumerate()
        .flat_map(|(i, &n)| std::iter::repeat_n((i + 1) as f64, n))
        .collect();
    let s = crate::report::stats::mean_se(&values);
    (s.mean, s.se)
}

/// The numbers a reader wants first: per condition n, reward, feedback, T, NFC, survey
/// medians; then each measure's Friedman and Holm-corrected pairwise p.
fn summary_md(spec: &StudySpec, r: &StudyResults) -> String {
    let mut md = format!(
        "# {}\n\n{} participants, {} with every condition trained and surveyed.\n\n",
        spec.title, r.participants, r.complete
    );
    let questions: Vec<&str> = spec.survey.iter().map(|q| q.id.as_str()).collect();
    let _ = writeln!(
        md,
        "| condition | n | ended early | cumulative reward | feedback % | T (s) | NFC | {} |",
        questions
            .iter()
            .map(|q| format!("{q} median"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(
        md,
        "|---|---:|---:|---:|---:|---:|---:|{}",
        "---:|".repeat(questions.len())
    );
    let pm = |m: &crate::report::stats::MeanSe| format!("{:.1} ± {:.1}", m.mean, m.se);
    for c in &r.conditions {
        let medians: Vec<String> = questions
            .iter()
            .map(|q| {
                c.survey
                    .get(*q)
                    .and_then(|s| s.median)
                    .map_or("–".into(), |m| format!("{m}"))
            })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            c.n,
            c.ended_early,
            pm(&c.cumulative_reward),
            pm(&c.feedback_pct),
            pm(&c.seconds),
            pm(&c.no_feedback),
            medians.join(" | ")
        );
    }
    md.push_str("\nWithin-subject tests (Friedman; pairwise two-sided Wilcoxon signed-rank, Holm-corrected; rank-biserial r):\n\n");
    let names: Vec<&str> = r.conditions.iter().map(|c| c.name.as_str()).collect();
    for m in &r.tests {
        let t = &m.tests;
        let friedman = t
            .friedman
            .as_ref()
            .map_or("Friedman not computable".into(), |f| {
                format!(
                    "Friedman chi2({}) = {:.2}, p = {:.3}, W = {:.2}",
                    f.df, f.statistic, f.p, f.kendall_w
                )
            });
        let pairs: Vec<String> = t
            .pairs
            .iter()
            .map(|p| {
                format!(
                    "{} vs {}: p_holm = {:.3}, r = {:.2}",
                    names[p.a], names[p.b], p.p_holm, p.test.rank_biserial
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "- {} (n = {}): {}; {}{}",
            m.measure,
            t.participants,
            friedman,
            pairs.join("; "),
            t.caution
                .as_deref()
                .map_or(String::new(), |c| format!(". Caution: {c}"))
        );
    }
    md
}
