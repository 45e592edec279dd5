//! Reproducing the paper's Figures 3 and 5: the experiment grid, its child processes, and the
//! tables and figures made from whatever runs have finished.
//!
//! - [`grid`] (pure): which runs a figure needs and the command line of each.
//! - [`runner`]: runs them through an executor, skipping finished ones; [`run_end`]: how a run
//!   ended, judged alike by every executor.
//! - The executors: [`local`] (`dualrep train` / `dualrep prefs` child processes, J at a time)
//!   and [`slurm`] (the same command lines as tasks of `sbatch` job arrays on a cluster).
//! - [`run_files`]: reads a run directory's `metrics.csv` / `alignment.csv` and `summary.json`.
//! - [`stats`], [`aggregate`] (pure): mean and standard error over seeds, on a common step grid
//!   for Figure 3 and per query for Figure 5.
//! - [`rank_test`] (pure): the one-sided exact Mann-Whitney U test over seeds.
//! - [`within_subject`] (pure): a human-subject study's participants x conditions scores:
//!   Friedman and Kendall's W, pairwise Wilcoxon signed-rank tests with Holm's correction, the
//!   one-sided paired test over seeds; tails from [`distributions`].
//! - [`table`] (pure): `table.md`, with the paper's published values beside ours.
//! - [`robustness`] (pure): the grid, numbers and table of `reproduce robustness` (simulated
//!   teachers that make mistakes).
//! - [`plot`]: the figures as SVG and PNG, text in the embedded [`font`].
//!
//! [`write_report`] ties the last four together for a grid directory.

pub mod aggregate;
pub mod distributions;
pub mod font;
pub mod grid;
pub mod local;
pub mod methods;
pub mod plot;
pub mod rank_test;
pub mod robustness;
pub mod run_end;
pub mod run_files;
pub mod runner;
pub mod slurm;
pub mod stats;
pub mod table;
pub mod within_subject;

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::Context;

use self::aggregate::{FIG3_GRID_POINTS, aggregate_fig3, aggregate_fig5};
use self::grid::Figure;

/// The files a report wrote, and how many finished runs went into them.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    pub table: PathBuf,
    pub svg: PathBuf,
    pub png: PathBuf,
    pub runs: usize,
}

/// Reads every finished run under `root` and writes `root/table.md`, `root/<fig>.svg` and
/// `root/<fig>.png`. Unfinished runs are left out, so this works on a partial grid too.
pub fn write_report(figure: Figure, root: &Path) -> anyhow::Result<Written> {
    fs::create_dir_all(root).with_context(|| format!("creating {}", root.display()))?;
    let written = Written {
        table: root.join("table.md"),
        svg: root.join(format!("{}.svg", figure.stem())),
        png: root.join(format!("{}.png", figure.stem())),
        runs: 0,
    };
    let (text, runs) = match figure {
        Figure::Fig3 => {
            let runs = run_files::load_train_runs(root)?;
            let tasks = aggregate_fig3(&runs, FIG3_GRID_POINTS);
            plot::write_figure(&tasks, &written.svg, &written.png)?;
            // A grid of the authors' runs as run is read against their own runs too.
            let as_run = !runs.is_empty() && runs.iter().all(|r| r.ran_as_run());
            (table::fig3_table(&tasks, as_run), runs.len())
        }
        Figure::Fig5 => {
            let runs = run_files::load_prefs_runs(root)?;
            let tasks = aggregate_fig5(&runs);
            plot::write_figure(&tasks, &written.svg, &written.png)?;
            (table::fig5_table(&tasks), runs.len())
        }
        Figure::Robustness => {
            let (train, prefs) = run_files::load_robustness_runs(root)?;
            let tasks = robustness::aggregate(&train, &prefs);
            let panels = plot::robustness::panels(&tasks);
            plot::write_figure(&panels, &written.svg, &written.png)?;
            (robustness::table(&tasks), train.len() + prefs.len())
        }
    };
    fs::write(&written.table, text)
        .with_context(|| format!("writing {}", written.table.display()))?;
    Ok(Written { runs, ..written })
}
