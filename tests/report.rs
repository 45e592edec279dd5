//! `table.md` and the figures from fixture grids (fake run directories in the documented
//! formats, see `report_fixtures`), through the library and through `dualrep reproduce
//! --report-only`.
//!
//! Set `REPORT_FIXTURE_OUT=DIR` to keep the fixture grids and their figures in DIR for a look.

use crate::report_fixtures;
use crate::support::cli::refused;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use dualrep::report::grid::Figure;
use dualrep::report::write_report;

/// A fresh directory for one test: under `REPORT_FIXTURE_OUT` when set (kept), else temporary.
fn workdir(name: &str) -> (Option<tempfile::TempDir>, PathBuf) {
    match std::env::var_os("REPORT_FIXTURE_OUT") {
        Some(root) => {
            let dir = Path::new(&root).join(name);
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).unwrap();
            (None, dir)
        }
        None => {
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path().to_path_buf();
            (Some(tmp), dir)
        }
    }
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

/// DREF's mean feedback percentage on `task` in the fixture, read from its summaries.
fn dref_pct(root: &Path, task: &str, seeds: u64) -> f64 {
    let total: f64 = (0..seeds)
        .map(|s| {
            let path = root
                .join(task)
                .join("dref")
                .join(format!("seed{s}/summary.json"));
            let v: serde_json::Value =
                serde_json::from_str(&fs::read_to_string(path).unwrap()).unwrap();
            100.0 * v["feedback_fraction"].as_f64().unwrap()
        })
        .sum();
    total / seeds as f64
}

#[test]
fn fig3_report_writes_table_svg_and_png_with_feedback_in_the_legend() {
    let (_keep, root) = workdir("fig3");
    report_fixtures::write_fig3_grid(&root, 5);
    let written = write_report(Figure::Fig3, &root).unwrap();
    assert_eq!(written.runs, 3 * 6 * 5);

    let svg = fs::read_to_string(&written.svg).unwrap();
    for task in ["lunar-lander", "reaching", "placing"] {
        let legend = format!("DREF ({:.1} %)", dref_pct(&root, task, 5));
        assert!(
            svg.contains(&legend),
            "{legend} missing from the SVG legend"
        );
    }
    for text in [
        "Lunar-Lander",
        "Reaching-Sim",
        "Placing-Sim",
        "EF-100%",
        "SAC",
        "EF-6.2%",
    ] {
        assert!(svg.contains(text), "{text} missing from the SVG");
    }
    assert!(svg.contains("Environment steps") && svg.contains("Cumulative reward"));

    let png = fs::read(&written.png).unwrap();
    assert_eq!(png_size(&png), (3 * 560, 440), "three panels side by side");
    assert!(
        png.len() > 20_000,
        "a PNG of {} bytes cannot hold three plots",
        png.len()
    );

    let table = fs::read_to_string(&written.table).unwrap();
    assert!(
        table.contains("## Lunar-Lander: 150k steps (paper: 150k)"),
        "{table}"
    );
    assert!(
        table.contains("## Reaching-Sim: 100k steps (paper: 100k)"),
        "{table}"
    );
    assert!(table.contains("| 1.17 | 34.1k (6.3 %) |"), "{table}");
    // The fixture's EF-8.4 is the paper's rate, not its DREF's (8.5 %), so it is named as one.
    assert!(
        table.contains("| EF-8.4% (a DREF's rate not in this table) |"),
        "{table}"
    );
    assert!(table.contains("| 0.23 | 10.1k |"), "{table}");
    // Every task has its six methods, and DREF's per-run table its five seeds.
    assert_eq!(
        table.matches("\n| ").count(),
        3 * (7 + 6),
        "header + 6 rows per task, header + 5 runs of DREF per task:\n{table}"
    );
    assert_eq!(table.matches("DREF, per run:").count(), 3, "{table}");
}

#[test]
fn fig5_report_writes_table_and_figure_with_the_four_methods() {
    let (_keep, root) = workdir("fig5");
    report_fixtures::write_fig5_grid(&root, 5);
    let written = write_report(Figure::Fig5, &root).unwrap();
    assert_eq!(written.runs, 3 * 4 * 5);
    let svg = fs::read_to_string(&written.svg).unwrap();
    for text in [
        "DRPL",
        "DRPL-SS",
        "Random fragment",
        "Full trajectory",
        "Number of queries",
    ] {
        assert!(svg.contains(text), "{text} missing from the SVG");
    }
    assert_eq!(png_size(&fs::read(&written.png).unwrap()), (3 * 560, 440));
    let table = fs::read_to_string(&written.table).unwrap();
    assert!(table.contains("## Placing-Sim: 40 queries"), "{table}");
    assert!(table.contains("| DRPL | 0.8"), "{table}");
    assert!(table.contains("| 13.5 ± 0.7 | 5 |"), "{table}");
}

#[test]
fn report_leaves_out_unfinished_runs_and_draws_an_empty_grid() {
    let (_keep, root) = workdir("partial");
    report_fixtures::write_fig3_grid(&root, 2);
    // An interrupted run: metrics so far, no summary.
    let dir = root.join("reaching/dref/seed2");
    fs::create_dir_all(&dir).unwrap();
    fs::write(dir.join("metrics.csv"), "step,episode\n1,2,3\n").unwrap();
    // Not runs at all.
    fs::create_dir_all(root.join("notes/dref/seed0")).unwrap();
    fs::create_dir_all(root.join("reaching/dref/seedling")).unwrap();
    assert_eq!(write_report(Figure::Fig3, &root).unwrap().runs, 3 * 6 * 2);

    let (_keep, empty) = workdir("empty");
    let written = write_report(Figure::Fig3, &empty).unwrap();
    assert_eq!(written.runs, 0);
    assert!(
        fs::read_to_string(&written.svg)
            .unwrap()
            .contains("no finished runs yet")
    );
    assert!(fs::metadata(&written.png).unwrap().len() > 0);
}

#[test]
fn report_names_the_file_of_a_finished_but_broken_run() {
    let (_keep, root) = workdir("broken");
    report_fixtures::write_fig3_grid(&root, 1);
    let bad = root.join("placing/sac/seed0/metrics.csv");
    fs::write(
        &bad,
        "step,episode,return,cumulative_return,feedback_count,feedback_fraction\n10,0,oops,1,0,0\n",
    )
    .unwrap();
    let err = format!("{:#}", write_report(Figure::Fig3, &root).unwrap_err());
    assert!(err.contains(&bad.display().to_string()), "{err}");
}

#[test]
fn reproduce_report_only_runs_nothing_and_writes_the_files() {
    let (_keep, root) = workdir("report-only");
    report_fixtures::write_fig5_grid(&root, 2);
    let out = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args(["reproduce", "fig5", "--report-only", "--out"])
        .arg(&root)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.starts_with("24 finished runs ->"), "{stdout}");
    for file in ["table.md", "fig5.svg", "fig5.png"] {
        assert!(fs::metadata(root.join(file)).unwrap().len() > 0, "{file}");
    }

    let missing = root.join("nowhere");
    let out = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args(["reproduce", "fig3", "--report-only", "--out"])
        .arg(&missing)
        .output()
        .unwrap();
    assert!(refused(&out).contains("is not a directory"));
}
